"""Eq. 1: per-pixel variance over seeds against a brute-force loop; streaming and stores."""

import numpy as np
import pytest
import xarray as xr

from stereovar.errors import StoreError
from stereovar.estimators.seeds import (
    StreamingVariance,
    variance_dataset,
    variance_field,
    variance_from_stores,
)
from stereovar.io.store import write_dataset


def brute_force(stack):
    """Eq. 1 with explicit loops: 1/N population variance per channel, averaged over RGB."""
    n, height, width, channels = stack.shape
    mean = np.zeros((height, width, channels))
    var = np.zeros((height, width))
    for j in range(height):
        for i in range(width):
            acc = 0.0
            for c in range(channels):
                m = sum(float(stack[k, j, i, c]) for k in range(n)) / n
                mean[j, i, c] = m
                acc += sum((float(stack[k, j, i, c]) - m) ** 2 for k in range(n)) / n
            var[j, i] = acc / channels
    return mean, var


def random_stack(n=6, height=5, width=4, seed=0):
    rng = np.random.default_rng(seed)
    return rng.gamma(2.0, 0.5, size=(n, height, width, 3)).astype(np.float32)


def as_radiance(image):
    return xr.DataArray(
        image, dims=("y", "x", "channel"), coords={"channel": ["R", "G", "B"]}, name="radiance"
    )


def write_renders(tmp_path, stack, prefix="left"):
    paths = []
    for k, image in enumerate(stack):
        path = tmp_path / f"{prefix}_{k:03d}.zarr"
        write_dataset(as_radiance(image), path)
        paths.append(path)
    return paths


def test_numpy_matches_brute_force():
    stack = random_stack()
    mean, var = variance_field(stack)
    ref_mean, ref_var = brute_force(stack)
    assert mean.shape == (5, 4, 3) and var.shape == (5, 4)
    assert mean.dtype == np.float64 and var.dtype == np.float64
    np.testing.assert_allclose(mean, ref_mean, rtol=1e-12)
    np.testing.assert_allclose(var, ref_var, rtol=1e-10)


def test_single_seed_has_zero_variance():
    stack = random_stack(n=1)
    mean, var = variance_field(stack)
    np.testing.assert_array_equal(var, 0.0)
    np.testing.assert_allclose(mean, stack[0])


def test_xarray_matches_brute_force_and_keeps_dims_and_coords():
    stack = random_stack(n=4, height=3, width=5, seed=2)
    da = xr.DataArray(
        stack,
        dims=("seed", "y", "x", "channel"),
        coords={"seed": np.arange(4), "y": np.arange(3) * 2, "channel": ["R", "G", "B"]},
    ).transpose("channel", "x", "seed", "y")
    mean, var = variance_field(da)
    ref_mean, ref_var = brute_force(stack)
    assert mean.dims == ("y", "x", "channel") and var.dims == ("y", "x")
    assert "seed" not in mean.coords and "channel" not in var.coords
    assert list(mean.channel.values) == ["R", "G", "B"]
    np.testing.assert_array_equal(var.y.values, [0, 2, 4])
    np.testing.assert_allclose(mean.values, ref_mean, rtol=1e-12)
    np.testing.assert_allclose(var.values, ref_var, rtol=1e-10)


def test_bad_shapes_are_rejected():
    with pytest.raises(ValueError, match="shape"):
        variance_field(np.zeros((3, 4, 5)))
    with pytest.raises(ValueError, match="dims"):
        variance_field(xr.DataArray(np.zeros((2, 3, 4, 3)), dims=("n", "y", "x", "channel")))


def test_streaming_equals_batch():
    stack = random_stack(n=7, seed=3)
    acc = StreamingVariance()
    assert acc.n == 0
    for image in stack:
        acc.update(image)
    mean, var = variance_field(stack)
    assert acc.n == 7
    np.testing.assert_allclose(acc.mean, mean, rtol=1e-12)
    np.testing.assert_allclose(acc.variance, var, rtol=1e-10)
    assert acc.finite.all() and (acc.n_nonfinite == 0).all()


def test_streaming_row_blocks_equal_whole_renders():
    stack = random_stack(n=5, height=7, seed=4)
    whole, blocks = StreamingVariance(), StreamingVariance(shape=stack.shape[1:])
    for image in stack:
        whole.update(as_radiance(image))
        for start in range(0, 7, 3):
            rows = slice(start, min(start + 3, 7))
            blocks.update(image[rows], rows=rows)
    assert blocks.n == 5
    np.testing.assert_allclose(blocks.variance, whole.variance, rtol=1e-12)
    np.testing.assert_allclose(blocks.mean, whole.mean, rtol=1e-12)


def test_streaming_misuse_is_reported():
    with pytest.raises(ValueError, match="shape="):
        StreamingVariance().update(np.zeros((2, 3, 3)), rows=slice(0, 2))
    acc = StreamingVariance(shape=(4, 3, 3))
    with pytest.raises(ValueError, match="no render"):
        _ = acc.variance
    acc.update(np.zeros((2, 3, 3)), rows=slice(0, 2))
    with pytest.raises(ValueError, match="every row"):
        _ = acc.n
    with pytest.raises(ValueError, match="expected"):
        acc.update(np.zeros((4, 2, 3)))


def test_streaming_is_accurate_with_a_large_offset():
    """Radiance 1e4 with noise 1e-3: a naive float32 sum of squares loses everything."""
    rng = np.random.default_rng(5)
    stack = 1e4 + 1e-3 * rng.standard_normal((50, 6, 5, 3))
    acc = StreamingVariance(shape=(6, 5, 3))
    for image in stack:
        for start in (0, 2, 4):
            acc.update(image[start : start + 2], rows=slice(start, start + 2))
    ref = np.var(stack, axis=0, dtype=np.float64).mean(axis=-1)
    np.testing.assert_allclose(acc.variance, ref, rtol=1e-7)
    assert np.all(ref > 0.5e-6)


def test_non_finite_values_are_flagged_and_do_not_poison_others():
    stack = random_stack(n=6, height=4, width=5, seed=6).astype(np.float64)
    stack[3, 1, 2, 0] = np.nan
    stack[0, 0, 0, 2] = np.inf
    stack[4, 0, 0, 1] = -np.inf
    stack[5, 3, 4, :] = np.nan
    acc = StreamingVariance()
    with np.errstate(all="raise"):
        for image in stack:
            acc.update(image)
    expected_counts = np.zeros((4, 5), dtype=int)
    expected_counts[1, 2] = 1
    expected_counts[0, 0] = 2
    expected_counts[3, 4] = 1
    np.testing.assert_array_equal(acc.n_nonfinite, expected_counts)
    assert acc.n_nonfinite.dtype == np.int32
    np.testing.assert_array_equal(acc.finite, expected_counts == 0)
    assert np.isfinite(acc.mean).all() and np.isfinite(acc.variance).all()
    bad = expected_counts > 0
    assert (acc.variance[bad] == 0).all() and (acc.mean[bad] == 0).all()
    ref_mean, ref_var = brute_force(np.where(np.isfinite(stack), stack, 0.0))
    np.testing.assert_allclose(acc.variance[~bad], ref_var[~bad], rtol=1e-10)
    np.testing.assert_allclose(acc.mean[~bad], ref_mean[~bad], rtol=1e-12)


@pytest.mark.parametrize("chunk_rows", [None, 2, 100])
def test_from_stores_matches_batch(tmp_path, chunk_rows):
    stack = random_stack(n=4, height=5, width=6, seed=7)
    paths = write_renders(tmp_path, stack)
    ds = variance_from_stores(paths, chunk_rows=chunk_rows)
    mean, var = variance_field(stack)
    assert ds.attrs["n_seeds"] == 4
    assert ds["mean"].dims == ("y", "x", "channel") and ds["mean"].dtype == np.float32
    assert ds["variance"].dims == ("y", "x") and ds["variance"].dtype == np.float64
    assert ds["finite"].dtype == bool and ds["n_nonfinite"].dtype == np.int32
    assert list(ds.channel.values) == ["R", "G", "B"]
    np.testing.assert_allclose(ds["variance"].values, var, rtol=1e-10)
    np.testing.assert_allclose(ds["mean"].values, mean, rtol=1e-6)


def test_from_stores_flags_non_finite_renders(tmp_path):
    stack = random_stack(n=3, height=4, width=4, seed=8)
    stack[1, 2, 3, 1] = np.nan
    ds = variance_from_stores(write_renders(tmp_path, stack))
    assert int(ds["n_nonfinite"].sum()) == 1 and not bool(ds["finite"][2, 3])
    assert float(ds["variance"][2, 3]) == 0.0
    assert np.isfinite(ds["variance"].values).all()


def test_variance_dataset_contract(tmp_path):
    left = random_stack(n=3, height=4, width=5, seed=9)
    right = random_stack(n=3, height=4, width=5, seed=10)
    ds = variance_dataset(write_renders(tmp_path, left), write_renders(tmp_path, right, "right"))
    assert list(ds.view.values) == ["left", "right"]
    assert ds["mean"].dims == ("view", "y", "x", "channel")
    for name in ("variance", "finite", "n_nonfinite"):
        assert ds[name].dims == ("view", "y", "x")
    assert ds.attrs["n_seeds"] == 3
    np.testing.assert_allclose(ds["variance"].sel(view="left"), variance_field(left)[1])
    np.testing.assert_allclose(ds["variance"].sel(view="right"), variance_field(right)[1])


def test_variance_dataset_needs_equal_seed_counts(tmp_path):
    stack = random_stack(n=3, height=2, width=2)
    paths = write_renders(tmp_path, stack)
    with pytest.raises(ValueError, match="same number of seeds"):
        variance_dataset(paths, paths[:2])


def assert_one_line_naming(exc_info, path):
    message = str(exc_info.value)
    assert "\n" not in message
    assert str(path) in message and " it with `stereovar run -j1" in message


def test_missing_chunk_is_a_store_error(tmp_path):
    paths = write_renders(tmp_path, random_stack(n=3, height=3, width=3))
    chunks = [p for p in (paths[1] / "radiance").iterdir() if not p.name.startswith(".")]
    assert chunks
    chunks[0].unlink()
    with pytest.raises(StoreError, match="chunks missing") as exc_info:
        variance_from_stores(paths)
    assert_one_line_naming(exc_info, paths[1])


def test_corrupt_chunk_is_a_store_error(tmp_path):
    paths = write_renders(tmp_path, random_stack(n=2, height=3, width=3))
    chunk = next(p for p in (paths[0] / "radiance").iterdir() if not p.name.startswith("."))
    chunk.write_bytes(chunk.read_bytes()[:5])
    with pytest.raises(StoreError) as exc_info:
        variance_from_stores(paths)
    assert_one_line_naming(exc_info, paths[0])


def test_shape_mismatch_between_seeds_is_a_store_error(tmp_path):
    paths = write_renders(tmp_path, random_stack(n=2, height=3, width=3))
    odd = tmp_path / "odd.zarr"
    write_dataset(as_radiance(random_stack(n=1, height=3, width=4)[0]), odd)
    with pytest.raises(StoreError, match="differs") as exc_info:
        variance_from_stores([*paths, odd])
    assert_one_line_naming(exc_info, odd)


def test_missing_store_or_array_is_a_store_error(tmp_path):
    missing = tmp_path / "missing.zarr"
    with pytest.raises(StoreError, match="does not exist") as exc_info:
        variance_from_stores([missing])
    assert_one_line_naming(exc_info, missing)
    wrong = tmp_path / "wrong.zarr"
    write_dataset(as_radiance(random_stack(n=1)[0]).rename("other"), wrong)
    with pytest.raises(StoreError, match="radiance") as exc_info:
        variance_from_stores([wrong])
    assert_one_line_naming(exc_info, wrong)
    partial = tmp_path / "partial.zarr"
    write_dataset(as_radiance(random_stack(n=1)[0]), partial)
    (partial / ".zmetadata").unlink()
    with pytest.raises(StoreError) as exc_info:
        variance_from_stores([partial])
    assert_one_line_naming(exc_info, partial)
