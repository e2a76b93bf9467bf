"""Tests of the block-shuffle decorrelation operator (paper Sec. 3.4)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from stereovar.intervention.shuffle import apply_block_permutation, block_permutation

from .reference.shuffle import decorrelate_right, split_residuals

# Sizes with edge strips on both sides: 4x5 full 8-px tiles, 3 bottom rows, 5 right columns.
H, W, B = 35, 45, 8


def tile_index_image(height, width, block):
    """Full-tile number (row-major) of every pixel, -1 outside the full tiles; explicit loops."""
    out = np.full((height, width), -1, dtype=np.int64)
    ny, nx = height // block, width // block
    for i in range(ny):
        for j in range(nx):
            for u in range(block):
                for v in range(block):
                    out[i * block + u, j * block + v] = i * nx + j
    return out


def brute_apply(field, perm, block):
    """Reference gather: destination tile k receives source tile perm[k], pixel by pixel."""
    field = np.asarray(field)
    out = field.copy()
    height, width = field.shape[:2]
    nx = width // block
    for k, src in enumerate(perm):
        di, dj = divmod(k, nx)
        si, sj = divmod(int(src), nx)
        for u in range(block):
            for v in range(block):
                out[di * block + u, dj * block + v] = field[si * block + u, sj * block + v]
    return out


def pop_variance_rgb(stack):
    """Population variance over seeds (axis 0) averaged over RGB, straight numpy."""
    stack = np.asarray(stack, dtype=np.float64)
    return stack.var(axis=0, ddof=0).mean(axis=-1)


@pytest.fixture
def renders():
    rng = np.random.default_rng(7)
    clean = rng.uniform(0.0, 1.0, size=(H, W, 3))
    sigma = rng.uniform(0.01, 0.2, size=(H, W, 1))
    return (clean + sigma * rng.normal(size=(12, H, W, 3))).astype(np.float32)


def test_permutation_moves_every_full_tile_exactly_once():
    perm = block_permutation(H, W, block=B, seed=3)
    tiles = tile_index_image(H, W, B)
    n_tiles = (H // B) * (W // B)
    assert perm.shape == (n_tiles,)
    moved = apply_block_permutation(tiles, perm, block=B)
    # Each destination tile is filled by a single source tile, and every source lands once.
    landed = []
    for i in range(H // B):
        for j in range(W // B):
            values = np.unique(moved[i * B : (i + 1) * B, j * B : (j + 1) * B])
            assert values.size == 1 and values[0] >= 0
            landed.append(int(values[0]))
    assert sorted(landed) == list(range(n_tiles))
    assert landed == [int(p) for p in perm]
    assert not np.array_equal(moved, tiles)  # 20 tiles: the identity has chance 1/20!


def test_edge_strips_are_unchanged():
    rng = np.random.default_rng(0)
    field = rng.normal(size=(H, W))
    moved = apply_block_permutation(field, block_permutation(H, W, block=B, seed=1), block=B)
    ry, rx = (H // B) * B, (W // B) * B
    np.testing.assert_array_equal(moved[ry:, :], field[ry:, :])
    np.testing.assert_array_equal(moved[:, rx:], field[:, rx:])
    # the full-tile region holds the same multiset of values
    np.testing.assert_array_equal(
        np.sort(moved[:ry, :rx], axis=None), np.sort(field[:ry, :rx], axis=None)
    )


def test_seed_determines_the_permutation():
    a = block_permutation(H, W, block=B, seed=11)
    np.testing.assert_array_equal(a, block_permutation(H, W, block=B, seed=11))
    perms = [tuple(block_permutation(64, 64, block=8, seed=s)) for s in range(5)]
    assert len(set(perms)) == 5  # 64 tiles: a collision has chance ~1/64!
    assert not np.array_equal(a, block_permutation(H, W, block=B, seed=12))


def test_block_one_and_whole_image():
    perm = block_permutation(4, 6, block=1, seed=0)
    assert sorted(perm.tolist()) == list(range(24))
    assert block_permutation(5, 7, block=5, seed=0).tolist() == [0]
    field = np.arange(35.0).reshape(5, 7)
    np.testing.assert_array_equal(apply_block_permutation(field, [0], block=5), field)


@pytest.mark.parametrize("shape", [(H, W), (H, W, 3)])
def test_apply_numpy_matches_brute_force(shape):
    rng = np.random.default_rng(2)
    field = rng.normal(size=shape).astype(np.float32)
    perm = block_permutation(H, W, block=B, seed=5)
    moved = apply_block_permutation(field, perm, block=B)
    assert moved.dtype == field.dtype and moved.shape == field.shape
    np.testing.assert_array_equal(moved, brute_apply(field, perm, B))


@pytest.mark.parametrize(
    "dims",
    [("y", "x"), ("x", "y"), ("y", "x", "channel"), ("channel", "x", "y"), ("x", "channel", "y")],
)
def test_apply_xarray_matches_brute_force(dims):
    rng = np.random.default_rng(4)
    base = rng.normal(size=(H, W, 3) if "channel" in dims else (H, W))
    canonical = ("y", "x", "channel")[: base.ndim]
    da = xr.DataArray(
        base,
        dims=canonical,
        coords={"y": np.arange(H), "x": np.arange(W) * 0.5},
        name="eps",
    ).transpose(*dims)
    perm = block_permutation(H, W, block=B, seed=9)
    moved = apply_block_permutation(da, perm, block=B)
    assert isinstance(moved, xr.DataArray)
    assert moved.dims == dims and moved.name == "eps"
    xr.testing.assert_identical(moved.coords.to_dataset(), da.coords.to_dataset())
    np.testing.assert_array_equal(moved.transpose(*canonical).values, brute_apply(base, perm, B))


def test_split_residuals(renders):
    clean, eps = split_residuals(renders)
    assert clean.dtype == np.float64 and eps.dtype == np.float64
    ref = np.zeros(renders.shape[1:], dtype=np.float64)
    for n in range(renders.shape[0]):
        ref += renders[n].astype(np.float64)
    ref /= renders.shape[0]
    np.testing.assert_allclose(clean, ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(clean[None] + eps, renders.astype(np.float64), rtol=0, atol=1e-12)
    np.testing.assert_allclose(eps.sum(axis=0), 0.0, atol=1e-12)


def test_split_residuals_xarray(renders):
    da = xr.DataArray(renders, dims=("seed", "y", "x", "channel")).transpose(
        "y", "seed", "channel", "x"
    )
    clean, eps = split_residuals(da)
    assert clean.dims == ("y", "channel", "x") and eps.dims == da.dims
    ref_clean, ref_eps = split_residuals(renders)
    np.testing.assert_allclose(clean.transpose("y", "x", "channel").values, ref_clean, atol=1e-12)
    np.testing.assert_allclose(
        eps.transpose("seed", "y", "x", "channel").values, ref_eps, atol=1e-12
    )


def test_decorrelate_keeps_the_clean_image(renders):
    out = decorrelate_right(renders, block=B, seed=3)
    assert out.dtype == np.float64 and out.shape == renders.shape
    ref_clean = renders.astype(np.float64).mean(axis=0)
    np.testing.assert_allclose(out.mean(axis=0), ref_clean, rtol=0, atol=1e-12)
    # and it actually changes the per-seed images
    assert not np.allclose(out, renders.astype(np.float64))


def test_decorrelated_variance_is_permuted_variance(renders):
    perm = block_permutation(H, W, block=B, seed=3)
    out = decorrelate_right(renders, block=B, seed=3)
    sigma2 = pop_variance_rgb(renders)
    np.testing.assert_allclose(
        pop_variance_rgb(out), brute_apply(sigma2, perm, B), rtol=1e-9, atol=1e-12
    )


def test_decorrelate_one_permutation_for_every_seed(renders):
    perm = block_permutation(H, W, block=B, seed=3)
    out = decorrelate_right(renders, block=B, seed=3)
    stack = renders.astype(np.float64)
    clean = stack.mean(axis=0)
    for n in range(stack.shape[0]):
        ref = clean + brute_apply(stack[n] - clean, perm, B)
        np.testing.assert_allclose(out[n], ref, rtol=0, atol=1e-12)


def test_decorrelate_xarray_matches_numpy(renders):
    da = xr.DataArray(
        renders, dims=("seed", "y", "x", "channel"), coords={"seed": np.arange(12) + 100}
    ).transpose("channel", "x", "seed", "y")
    out = decorrelate_right(da, block=B, seed=3)
    assert isinstance(out, xr.DataArray) and out.dims == da.dims
    np.testing.assert_array_equal(out["seed"].values, da["seed"].values)
    np.testing.assert_allclose(
        out.transpose("seed", "y", "x", "channel").values,
        decorrelate_right(renders, block=B, seed=3),
        rtol=0,
        atol=1e-12,
    )


def test_decorrelate_grayscale_stack():
    rng = np.random.default_rng(1)
    stack = rng.normal(size=(6, 16, 24))
    perm = block_permutation(16, 24, block=8, seed=0)
    out = decorrelate_right(stack, block=8, seed=0)
    clean = stack.mean(axis=0)
    for n in range(6):
        np.testing.assert_allclose(
            out[n], clean + brute_apply(stack[n] - clean, perm, 8), atol=1e-12
        )


@pytest.mark.parametrize("block", [0, -3, 36, 46, 1000])
def test_bad_block_size_raises_one_line(block):
    with pytest.raises(ValueError) as info:
        block_permutation(H, W, block=block)
    message = str(info.value)
    assert "\n" not in message
    assert "block" in message and f"block={block}" in message and f"{H}x{W}" in message


@pytest.mark.parametrize("block", [0, 36])
def test_bad_block_size_raises_in_apply_and_decorrelate(block, renders):
    with pytest.raises(ValueError, match=f"block={block}"):
        apply_block_permutation(np.zeros((H, W)), np.arange(1), block=block)
    with pytest.raises(ValueError, match=f"block={block}"):
        decorrelate_right(renders, block=block)


def test_wrong_permutation_is_rejected():
    with pytest.raises(ValueError, match="perm"):
        apply_block_permutation(np.zeros((H, W)), np.arange(5), block=B)
    with pytest.raises(ValueError, match="perm"):
        apply_block_permutation(np.zeros((H, W)), np.zeros(20, dtype=int), block=B)
