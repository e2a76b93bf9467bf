"""What a generator ships: Blender's view transform and PNG (stereovar.transforms.output), the
chains a shipped matched null passes through, and the rows that measure what ships."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter, shift

pytest.importorskip("bpy")

from stereovar.calibration.renders import QUANTISED_SHARE, renders_output_rows  # noqa: E402
from stereovar.calibration.scene_frames import SceneFrames  # noqa: E402
from stereovar.calibration.stacks import transform_stack  # noqa: E402
from stereovar.calibration.synthesis import draw_frames  # noqa: E402
from stereovar.io.transfer import linear_to_srgb, srgb_to_linear  # noqa: E402
from stereovar.statistics.fields import AnalysisSettings  # noqa: E402
from stereovar.transforms import TransformInputs, get_transform, transform_chain  # noqa: E402
from stereovar.transforms.output import view_png_codes  # noqa: E402

H, W, D = 64, 96, 2.5


@pytest.mark.parametrize("bits", [8, 16])
def test_the_standard_view_transform_is_the_srgb_curve_rounded(bits):
    """Blender's Standard view transform is the sRGB curve alone: its PNG codes equal the
    sRGB encoding of the clipped value rounded to 2^B - 1 levels (within one code, which
    Blender's colour lookup may differ by), and full scale clips."""
    rng = np.random.default_rng(0)
    x = rng.uniform(0.0, 1.3, (30, 40, 3)).astype(np.float32)
    codes = view_png_codes(x, view_transform="Standard", bits=bits).astype(np.int64)
    full = 2**bits - 1
    expected = np.rint(full * linear_to_srgb(np.clip(x, 0.0, 1.0))).astype(np.int64)
    assert np.abs(codes - expected).max() <= 1
    assert np.mean(codes == expected) > 0.85
    assert (codes[x >= 1.0] == full).all()


def test_filmic_puts_middle_grey_at_half_and_compresses_highlights():
    """Filmic maps scene middle grey (0.18) to display 0.5 (code 128 of 255), rises
    monotonically and keeps detail above 1 where the sRGB curve clips."""
    ramp = np.geomspace(1e-3, 8.0, 64, dtype=np.float32)
    image = np.repeat(np.repeat(ramp[None, :, None], 2, axis=0), 3, axis=2)
    filmic = view_png_codes(image, view_transform="Filmic")[0, :, 0].astype(int)
    standard = view_png_codes(image, view_transform="Standard")[0, :, 0].astype(int)
    grey = view_png_codes(np.full((2, 2, 3), 0.18, np.float32), view_transform="Filmic")
    assert abs(int(grey[0, 0, 0]) - 128) <= 1
    assert (np.diff(filmic) >= 0).all()
    above = ramp > 1.0
    assert (standard[above] == 255).all() and filmic[above].min() < 245


def test_what_the_current_scene_is_set_to_changes_nothing():
    """Other code may leave Blender's current scene writing multilayer EXR at another
    exposure; the PNG is written by a scene of its own."""
    import bpy

    scene = bpy.context.scene
    settings = scene.render.image_settings
    before = (getattr(settings, "media_type", None), settings.file_format,
              scene.view_settings.exposure)
    try:
        if hasattr(settings, "media_type"):
            settings.media_type = "MULTI_LAYER_IMAGE"
        settings.file_format = "OPEN_EXR_MULTILAYER"
        scene.view_settings.exposure = 3.0
        grey = view_png_codes(np.full((2, 2, 3), 0.18, np.float32), view_transform="Filmic")
        assert abs(int(grey[0, 0, 0]) - 128) <= 1
        assert settings.file_format == "OPEN_EXR_MULTILAYER"
    finally:
        if before[0] is not None:
            settings.media_type = before[0]
        settings.file_format, scene.view_settings.exposure = before[1], before[2]


def test_the_shipped_image_is_read_back_as_an_audit_reads_its_png():
    """The transform's output is the sRGB decoding of the PNG's codes over full scale; a
    non-finite render value stays NaN."""
    rng = np.random.default_rng(1)
    render = rng.uniform(0.0, 2.0, (16, 24, 3)).astype(np.float32)
    render[3, 4, 1] = np.nan
    out = get_transform("png8_filmic")(
        TransformInputs(render=render, view="left", seed_index=0, rng_seed=0)
    )
    clean = np.nan_to_num(render)
    codes = view_png_codes(clean, view_transform="Filmic", bits=8)
    expected = srgb_to_linear(codes / 255.0)
    finite = np.isfinite(render)
    assert np.isnan(out[~finite]).all()
    np.testing.assert_allclose(out[finite], expected[finite], rtol=1e-6, atol=1e-7)
    assert get_transform("png8_filmic").encoding == {"bits": 8, "transfer": "srgb",
                                                     "scale": 1.0}


def test_a_chain_applies_each_link_to_the_previous_links_outputs():
    """``a+b`` equals ``b`` applied to ``a``'s N outputs, each link with its own seed."""
    from stereovar.seeding import derive_seed

    rng = np.random.default_rng(2)
    frames = rng.uniform(0.05, 0.8, (4, 12, 16, 3)).astype(np.float32)
    chained = transform_stack("equalise+png8_agx", frames, view="left", seed=5)
    first = transform_stack("equalise", frames, view="left", seed=derive_seed(5, "equalise"))
    expected = transform_stack("png8_agx", first, view="left",
                               seed=derive_seed(5, "png8_agx"))
    np.testing.assert_array_equal(chained, expected)
    assert [t.name for t in transform_chain("equalise+png8_agx")] == ["equalise", "png8_agx"]


@pytest.fixture(scope="module")
def textured_scene(textured_pair):
    """A grey textured scene whose right view is the left 2.5 px further right."""
    mean, truth = textured_pair(H, W, D, 11)
    variance = {v: 0.01 * m.mean(axis=-1) for v, m in mean.items()}
    return SceneFrames(mean, variance, truth, np.zeros((H, W), bool), 1, 8, "texture|spp8")


def _rows(frames, scene):
    rows = renders_output_rows(frames, scene, outputs={"denoise+png8_filmic": "png8_filmic"},
                               settings=AnalysisSettings())
    assert {r["transform"] for r in rows} == {"denoise+png8_filmic"}
    assert {r["kind"] for r in rows} == {"renders"}
    return {r["method"]: r for r in rows}


def test_what_ships_keeps_a_planted_cue_and_reads_none_without_one(textured_scene):
    """Noise of a few codes through the PNG: a variance pattern both views share (a planted
    cue, moved with the disparity) reads clearly above 0 in the intensity-controlled rho of
    what ships, independent camera-law noise about 0, and the codes fix almost no pixel."""
    rng = np.random.default_rng(3)
    mean = textured_scene.mean
    pattern = gaussian_filter(rng.normal(0.0, 1.0, (H, W)), 2.0)
    pattern /= pattern.std()
    gain = {"left": np.exp(0.8 * pattern), "right": np.exp(0.8 * shift(pattern, (0, D),
                                                                         order=1, mode="nearest"))}
    for planted in (True, False):
        frames = {}
        for view, m in mean.items():
            var = 4e-3 * m.mean(axis=-1) * (gain[view] if planted else 1.0)
            frames[view] = draw_frames(m, var, 8, rng)
        rows = _rows(frames, textured_scene)
        partial = rows["partial"]
        assert rows[QUANTISED_SHARE]["rho"] < 0.05
        if planted:
            assert partial["boot_low"] > 0.2
        else:
            assert abs(partial["rho"]) < 0.05 and partial["boot_low"] < 0.0 < partial["boot_high"]


def test_what_ships_below_one_code_is_undefined_with_its_share(textured_scene):
    """Noise far below one 8-bit code: every frame of a pixel falls on one or two codes, so
    the share is about 1 and the intensity-controlled rho is undefined (NaN), not 0."""
    rng = np.random.default_rng(4)
    frames = {v: draw_frames(m, (1e-4 * m.mean(axis=-1)) ** 2, 8, rng)
              for v, m in textured_scene.mean.items()}
    rows = _rows(frames, textured_scene)
    assert rows[QUANTISED_SHARE]["rho"] > 0.95
    assert math.isnan(rows["partial"]["rho"])
