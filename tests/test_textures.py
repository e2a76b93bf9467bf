"""Tests of the procedural texture baker (stereovar.scenes.textures)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from stereovar.scenes.textures import PATTERNS, bake_texture

COLORS = {
    "planks": [[0.45, 0.28, 0.14], [0.25, 0.13, 0.06], [0.6, 0.4, 0.2]],
    "tiles": [[0.7, 0.7, 0.68], [0.5, 0.55, 0.6], [0.2, 0.2, 0.2]],
    "noise": [[0.75, 0.72, 0.65], [0.55, 0.5, 0.45]],
    "stripes": [[0.6, 0.2, 0.2], [0.8, 0.75, 0.6], [0.2, 0.3, 0.5]],
    "checker": [[0.8, 0.8, 0.8], [0.1, 0.1, 0.1]],
    "grain": [[0.55, 0.35, 0.18], [0.3, 0.16, 0.07]],
}


def spec(pattern, *, seed=3, resolution=128, **extra):
    return {
        "pattern": pattern,
        "colors": COLORS[pattern],
        "seed": seed,
        "resolution": resolution,
        **extra,
    }


def luminance(img):
    return img.astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])


def box_blur(a, radius=2):
    """Periodic box blur (the textures tile, so wrap-around is the right boundary)."""
    out = np.zeros_like(a)
    k = 2 * radius + 1
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            out += np.roll(a, (dy, dx), axis=(0, 1))
    return out / (k * k)


@pytest.mark.parametrize("pattern", PATTERNS)
def test_deterministic(pattern):
    a = bake_texture(spec(pattern))
    b = bake_texture(spec(pattern))
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("pattern", PATTERNS)
@pytest.mark.parametrize("resolution", [16, 100, 256])
def test_shape_dtype_range(pattern, resolution):
    img = bake_texture(spec(pattern, resolution=resolution))
    assert img.shape == (resolution, resolution, 3)
    assert img.dtype == np.float32
    assert np.isfinite(img).all()
    assert img.min() >= 0.0 and img.max() <= 1.0


@pytest.mark.parametrize("pattern", PATTERNS)
def test_has_fine_texture(pattern):
    """Stereo needs local detail: high-pass energy and global contrast above thresholds."""
    lum = luminance(bake_texture(spec(pattern, resolution=256)))
    high_pass = lum - box_blur(lum, radius=2)
    assert high_pass.std() > 0.01, high_pass.std()
    # detail everywhere, not only in a few places: most 16x16 blocks carry texture
    blocks = high_pass.reshape(16, 16, 16, 16).std(axis=(1, 3))
    assert np.mean(blocks > 0.005) > 0.95
    assert lum.std() > 0.03
    # gradients: mean absolute finite difference well above float noise
    assert np.abs(np.diff(lum, axis=1)).mean() > 0.005
    assert np.abs(np.diff(lum, axis=0)).mean() > 0.005


def seam_ratio(lum, axis):
    """Mean jump across the border over the largest mean jump between neighbouring lines.

    A tileable texture continues across its border, so the border is no worse than the
    sharpest line pair inside it (a cell edge of a checker, a grout line, a board gap).
    """
    inner = np.abs(np.diff(lum, axis=axis)).mean(axis=1 - axis)
    seam = np.abs(np.take(lum, 0, axis=axis) - np.take(lum, -1, axis=axis)).mean()
    return seam / inner.max()


@pytest.mark.parametrize("pattern", PATTERNS)
@pytest.mark.parametrize("resolution", [128, 200])
def test_tileable(pattern, resolution):
    lum = luminance(bake_texture(spec(pattern, resolution=resolution)))
    for axis in (0, 1):
        assert seam_ratio(lum, axis) <= 1.05, (axis, seam_ratio(lum, axis))


@pytest.mark.parametrize("pattern", ["noise", "grain", "planks"])
def test_seam_check_detects_non_tileable(pattern):
    """Control for test_tileable: an off-grid crop (not periodic) fails the same criterion."""
    big = luminance(bake_texture(spec(pattern, resolution=256)))
    crop = big[37:165, 11:139]
    assert max(seam_ratio(crop, 0), seam_ratio(crop, 1)) > 1.05


@pytest.mark.parametrize("pattern", PATTERNS)
def test_seeds_differ(pattern):
    a = bake_texture(spec(pattern, seed=0))
    b = bake_texture(spec(pattern, seed=1))
    assert np.abs(a - b).mean() > 0.01


def test_repeat_is_not_baked():
    a = bake_texture(spec("planks"))
    b = bake_texture(spec("planks", repeat=[4.0, 2.5]))
    np.testing.assert_array_equal(a, b)


def test_colors_change_output():
    a = bake_texture(spec("noise"))
    b = bake_texture({**spec("noise"), "colors": [[0.2, 0.3, 0.4], [0.1, 0.1, 0.1]]})
    assert not np.array_equal(a, b)


@pytest.mark.parametrize("seed", [0, 1, 7])
@pytest.mark.parametrize("resolution", [64, 100, 256])
def test_checker_matches_brute_force(seed, resolution):
    """Each texel is nearer colors[0] where (i + j) is even and colors[1] where it is odd.

    The number of cells per side is drawn from the seed; it must be even (so the pattern
    tiles) and one of the counts must reproduce the texture exactly.
    """
    c0, c1 = [0.85, 0.85, 0.85], [0.05, 0.05, 0.05]
    img = bake_texture(
        {"pattern": "checker", "colors": [c0, c1], "seed": seed, "resolution": resolution}
    )
    observed = np.linalg.norm(img - np.asarray(c0), axis=-1) > np.linalg.norm(
        img - np.asarray(c1), axis=-1
    )  # True where nearer colors[1]
    best = None
    for cells in range(2, 33, 2):
        ref = np.zeros((resolution, resolution), dtype=bool)
        for row in range(resolution):
            for col in range(resolution):
                i = int(np.floor((row + 0.5) / resolution * cells))
                j = int(np.floor((col + 0.5) / resolution * cells))
                ref[row, col] = (i + j) % 2 == 1
        agree = np.mean(ref == observed)
        if best is None or agree > best[0]:
            best = (agree, cells)
    assert best[0] == 1.0, best
    # the top-left cell is colors[0]
    assert not observed[0, 0]


def test_invalid_specs():
    with pytest.raises(ValueError, match="pattern"):
        bake_texture({"pattern": "marble", "colors": [[0, 0, 0], [1, 1, 1]]})
    with pytest.raises(ValueError, match="colors"):
        bake_texture({"pattern": "noise", "colors": [[0, 0, 0]]})
    with pytest.raises(ValueError, match="resolution"):
        bake_texture({"pattern": "noise", "colors": [[0, 0, 0], [1, 1, 1]], "resolution": 8})


def test_fast_enough():
    """Generous bounds (the targets are < 50 ms at 256^2 and < 1 s at 1024^2)."""
    for pattern in PATTERNS:
        bake_texture(spec(pattern, resolution=256))  # warm up
        t0 = time.perf_counter()
        bake_texture(spec(pattern, resolution=256))
        assert time.perf_counter() - t0 < 0.25, pattern
    t0 = time.perf_counter()
    bake_texture(spec("grain", resolution=1024))
    assert time.perf_counter() - t0 < 3.0


def test_cached_bake_equals_bake_and_survives_a_corrupt_cache(tmp_path):
    from stereovar.scenes.textures import bake_texture, bake_texture_cached

    spec = {
        "pattern": "planks",
        "colors": [[0.2, 0.1, 0.05], [0.7, 0.5, 0.3]],
        "seed": 3,
        "resolution": 64,
    }
    expected = bake_texture(spec)
    first = bake_texture_cached(spec, cache_dir=tmp_path)
    files = list(tmp_path.glob("*.npy"))
    assert len(files) == 1
    np.testing.assert_array_equal(first, expected)
    np.testing.assert_array_equal(bake_texture_cached(spec, cache_dir=tmp_path), expected)
    files[0].write_bytes(b"not an array")
    np.testing.assert_array_equal(bake_texture_cached(spec, cache_dir=tmp_path), expected)
    other = bake_texture_cached({**spec, "seed": 4}, cache_dir=tmp_path)
    assert not np.array_equal(other, expected)
    assert len(list(tmp_path.glob("*.npy"))) == 2


# --------------------------------------------------------------------------------------------
# the baked-texture cache verifies what it reads
# --------------------------------------------------------------------------------------------

CACHED = {
    "pattern": "planks",
    "colors": [[0.2, 0.1, 0.05], [0.7, 0.5, 0.3]],
    "seed": 5,
    "resolution": 64,
}


def damaged_warnings(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if "is damaged" in r.getMessage()]


def test_a_scaled_cached_texture_is_rebaked_with_one_warning(tmp_path, caplog):
    from stereovar.scenes.textures import bake_texture_cached

    fresh = bake_texture(CACHED)  # baked from scratch, no cache involved
    bake_texture_cached(CACHED, cache_dir=tmp_path)
    (path,) = tmp_path.glob("*.npy")
    np.save(path, np.load(path) * np.float32(0.25))  # what a damaged cache looks like
    image = bake_texture_cached(CACHED, cache_dir=tmp_path)
    np.testing.assert_array_equal(image, fresh)
    (line,) = damaged_warnings(caplog)
    assert str(path) in line and "SHA-256" in line and "\n" not in line
    # the cache holds the clean bake again, and reading it warns no more
    np.testing.assert_array_equal(np.load(path), fresh)
    caplog.clear()
    np.testing.assert_array_equal(bake_texture_cached(CACHED, cache_dir=tmp_path), fresh)
    assert damaged_warnings(caplog) == []


def test_a_2x2_array_in_place_of_a_texture_is_rebaked(tmp_path, caplog):
    import hashlib
    import json

    from stereovar.scenes.textures import bake_texture_cached

    fresh = bake_texture(CACHED)
    bake_texture_cached(CACHED, cache_dir=tmp_path)
    (path,) = tmp_path.glob("*.npy")
    tiny = np.full((2, 2, 3), 0.5, np.float32)  # float32 RGB, as a texture, but 2x2
    np.save(path, tiny)
    np.testing.assert_array_equal(bake_texture_cached(CACHED, cache_dir=tmp_path), fresh)
    assert len(damaged_warnings(caplog)) == 1
    from stereovar.scenes.textures import texture_cache_paths

    _, record = texture_cache_paths(CACHED, tmp_path)
    # the same array with a record that matches its bytes: refused for its shape
    np.save(path, tiny)
    meta = json.loads(record.read_text())
    record.write_text(json.dumps({**meta, "sha256": hashlib.sha256(path.read_bytes()).hexdigest()}))
    caplog.clear()
    np.testing.assert_array_equal(bake_texture_cached(CACHED, cache_dir=tmp_path), fresh)
    (line,) = damaged_warnings(caplog)
    assert "(2, 2, 3)" in line and "(64, 64, 3)" in line


def test_a_cached_texture_without_its_record_is_not_used(tmp_path):
    from stereovar.scenes.textures import bake_texture_cached, texture_cache_paths

    path, record = texture_cache_paths(CACHED, tmp_path)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.save(path, bake_texture(CACHED) * np.float32(0.25))  # a bare .npy, no record
    np.testing.assert_array_equal(
        bake_texture_cached(CACHED, cache_dir=tmp_path), bake_texture(CACHED)
    )
    assert record.exists()


def test_the_record_describes_the_stored_bytes(tmp_path):
    import hashlib
    import json

    from stereovar.scenes.textures import bake_texture_cached, texture_cache_paths

    image = bake_texture_cached(CACHED, cache_dir=tmp_path)
    path, record = texture_cache_paths(CACHED, tmp_path)
    meta = json.loads(record.read_text())
    assert meta["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    assert meta["shape"] == [64, 64, 3] and meta["dtype"] == "float32"
    assert not image.flags.writeable  # shared by the compilers of one process
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([path.name, record.name])


WALL_SCENE = """\
name: textured_wall
camera: {origin: [0.0, 0.0, 0.0], target: [0.0, 0.0, 3.0], up: [0.0, 1.0, 0.0], fov_deg: 50.0}
textures:
  paper: {pattern: stripes, colors: [[0.7, 0.6, 0.5], [0.2, 0.3, 0.4]], seed: 7, resolution: 64}
materials:
  paper: {type: diffuse, texture: paper}
objects:
- name: wall
  shape: rectangle
  material: paper
  transform: {translate: [0.0, 0.0, 3.0], rotate: [0.0, 180.0, 0.0], scale: [3.0, 3.0, 1.0]}
lights:
- name: lamp
  radiance: [20.0, 20.0, 20.0]
  transform: {translate: [1.5, 0.0, 0.5], scale: [0.3, 0.3, 1.0]}
"""
"""A textured wall lit from beside the camera: a scene that compiles in a moment."""


def test_renders_and_the_render_cache_never_hold_damaged_texture_pixels(
    mi, tmp_path, monkeypatch, caplog
):
    """A render job reading a damaged texture cache renders (and caches) exactly what a job
    with a clean cache does."""
    from stereovar.io.cache import RenderCache
    from stereovar.io.store import open_dataset
    from stereovar.jobs.render import render_job
    from stereovar.renderers.mitsuba.scene import baked_texture

    monkeypatch.setenv("STEREOVAR_CACHE_DIR", str(tmp_path / "cache"))
    rig = {"width": 32, "height": 18, "baseline_m": 0.026, "convention": "paper"}
    spec = tmp_path / "textured_wall.yaml"
    spec.write_text(WALL_SCENE)

    def run(name):
        baked_texture.cache_clear()  # the per-process cache of bakes: read the disk again
        outs = {v: tmp_path / f"{name}_{v}.zarr" for v in ("left", "right")}
        render_job(spec, outs, seeds=[0], spp=2, cache=tmp_path / f"renders_{name}", **rig)
        return [open_dataset(outs[v])["radiance"].values for v in ("left", "right")]

    try:
        clean = run("clean")
        (texture,) = sorted((tmp_path / "cache" / "textures").glob("*.npy"))
        np.save(texture, np.load(texture) * np.float32(0.25))
        damaged = run("damaged")
    finally:
        baked_texture.cache_clear()
    assert clean[0].mean() > 0.01  # the wall is lit and seen
    for a, b in zip(clean, damaged, strict=True):
        np.testing.assert_array_equal(a, b)
    assert len(damaged_warnings(caplog)) == 1
    entries = {p.name: p for p in (tmp_path / "renders_clean").rglob("*.zarr") if p.is_dir()}
    cache = RenderCache(tmp_path / "renders_damaged")
    assert len(entries) == 2 and sorted(entries) == sorted(
        p.name for p in cache.root.rglob("*.zarr") if p.is_dir()
    )
    for name, path in entries.items():
        np.testing.assert_array_equal(
            cache.get(name.removesuffix(".zarr")), open_dataset(path)["radiance"].values
        )
