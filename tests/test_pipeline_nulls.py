"""Camera pipelines with no Monte Carlo cue, outside the camera null's class
(stereovar.calibration.pipelines): the verdict rule must not call any of them a cue."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

from stereovar.calibration.pipelines import (
    PIPELINES,
    draw_pipeline,
    encoded_clean,
    integer_roundtrip,
    shading_gain,
)
from stereovar.calibration.replicates import scene_calibration
from stereovar.calibration.rules import MIN_EFFECT
from stereovar.calibration.scene_frames import SceneFrames
from stereovar.calibration.summary import calibration_table
from stereovar.calibration.synthesis import camera_law, draw_frames
from stereovar.calibration.view_statistics import statistic_rows
from stereovar.estimators.seeds import variance_field
from stereovar.intervention.lift import LIFT_METHOD
from stereovar.statistics.fields import AnalysisSettings

H, W, D = 72, 112, 2.5


@pytest.fixture(scope="module")
def coloured_scene():
    """A textured, coloured scene (each pixel's colour from three smooth fields) whose right
    view is the left 2.5 px further right (bilinear, as a real disparity falls between
    pixels): white balance and colour matrices make its noise depend on colour at a fixed
    brightness."""
    from scipy.ndimage import shift
    rng = np.random.default_rng(11)
    texture = gaussian_filter(rng.normal(0.0, 1.0, (H, W)), 1.5)
    mu = np.exp(1.0 * texture / texture.std() - 1.0)
    colour = np.stack([np.exp(0.6 * gaussian_filter(rng.normal(0, 1, (H, W)), 4) /
                              gaussian_filter(rng.normal(0, 1, (H, W)), 4).std())
                       for _ in range(3)], axis=-1)
    left = mu[..., None] * colour / colour.mean(axis=-1, keepdims=True)
    right = np.stack([shift(left[..., c], (0, D), order=1, mode="nearest") for c in range(3)],
                     axis=-1)
    mean = {"left": left, "right": right}
    truth = {v: {"disparity": np.full((H, W), D), "valid": np.ones((H, W), bool)}
             for v in mean}
    variance = {v: 0.02 * m.mean(axis=-1) + 1e-4 for v, m in mean.items()}
    return SceneFrames(mean, variance, truth, np.zeros((H, W), bool), 1, 8, "coloured|spp8")


def test_no_pipeline_is_called_a_cue(coloured_scene):
    """Every pipeline, read against its matched null (the camera null, or for 8-bit sRGB the
    camera law through the same encoding): the rule above the null fires on none of the
    replicates, and the Monte Carlo-specific rho stays below the smallest cue called."""
    rows, info = scene_calibration(
        coloured_scene, transforms=["none"], settings=AnalysisSettings(), replicates=3,
        strength_factors=[1.0], expensive_replicates=0, pipelines=PIPELINES,
        pipeline_replicates=3, min_strength=0.5,
    )
    assert info["pipeline_replicates"] == 3
    table, _ = calibration_table([{**r, "scene": "s"} for r in rows],
                                 methods=("partial", "shared_streams", LIFT_METHOD))
    # 8-bit sRGB at 0.2 DN: the encoding fixes the variance at nearly every pixel, so the
    # intensity-controlled rho is undefined there (and the matching rule, which needs it)
    undefined = {"srgb8_0.2"}
    assert all(np.isnan(r["rho"]) for r in rows
               if (r["kind"], r["method"]) == ("srgb8_0.2", "partial"))
    for method, rule in (("partial", "above_null"), ("shared_streams", "shared"),
                         (LIFT_METHOD, "matching")):
        fired = {r["kind"]: r["value"] for r in table
                 if (r["check"], r["rule"], r["scope"], r["method"])
                 == ("false_positive_rate", rule, "scene", method)}
        assert set(PIPELINES) - (undefined if method != "shared_streams" else set()) <= set(
            fired)
        assert {k: v for k, v in fired.items() if v > 0} == {}
    # the planted cue is still found (power is not given away for the pipelines)
    power = next(r for r in table if (r["check"], r["rule"], r["scope"], r["strength_factor"])
                 == ("power", "above_null", "scene", 1.0))
    assert power["value"] == 1.0


@pytest.mark.parametrize("pipeline", ["shading", "white_balance"])
def test_the_control_on_brightness_alone_would_call_them_a_cue(coloured_scene, pipeline,
                                                              monkeypatch):
    """What the control's colour and position terms are for: on lens shading and white
    balance the intensity-controlled rho with brightness alone is well above the smallest
    cue called; with them it is not."""
    from stereovar.controls import partial as intensity_control

    rng = np.random.default_rng(5)
    frames = draw_pipeline(pipeline, coloured_scene.mean, (0.02, 1e-4), 8, rng)

    def partial():
        rows = statistic_rows(frames, coloured_scene, AnalysisSettings(), "p",
                              methods=("partial",))
        return rows[0]["rho"]

    full = partial()
    original = intensity_control.partial_pair

    def brightness_only(*args, covariates=None, **kwargs):
        return original(*args, **kwargs)

    monkeypatch.setattr(intensity_control, "partial_pair", brightness_only)
    alone = partial()
    assert alone > MIN_EFFECT
    assert full < alone / 3


def test_shading_gain_is_four_at_the_corners_and_one_at_the_centre():
    g = shading_gain((41, 61))
    assert g[20, 30] == 1.0 and g[0, 0] == pytest.approx(4.0) and g[-1, -1] == pytest.approx(4.0)
    assert g[0, 30] == pytest.approx(1 + 3 * 20**2 / (20**2 + 30**2))


def test_integer_roundtrip_is_the_imports_decoding():
    """8-bit sRGB: a code value c decodes to sRGB^-1(c / 255) times the full scale, and every
    value encodes to the nearest code."""
    from stereovar.io.transfer import srgb_to_linear

    codes = np.arange(256)
    linear = srgb_to_linear(codes / 255.0) * 2.0
    assert np.allclose(integer_roundtrip(linear, bits=8, transfer="srgb", scale=2.0), linear,
                       atol=1e-6)
    between = 0.5 * (linear[100] + linear[101]) * np.array([0.999, 1.001])
    out = integer_roundtrip(between, bits=8, transfer="srgb", scale=2.0)
    assert set(np.round(out, 6)) <= set(np.round(linear.astype(np.float32), 6))


def test_encoded_law_finds_the_level_before_the_encoding():
    """Frames at a known law through 8-bit sRGB: the law fitted to the decoded frames is off
    (quantisation adds or hides variance); the encoded law around the dequantised clean image
    recovers the law before it."""
    rng = np.random.default_rng(2)
    clean = np.repeat(np.linspace(0.05, 0.6, 48 * 64).reshape(48, 64, 1), 3, axis=-1)
    law = (2e-6, 1e-7)
    encoding = {"bits": 8, "transfer": "srgb", "scale": 1.0}
    frames = integer_roundtrip(draw_frames(clean, law[0] * clean + law[1], 16, rng), **encoding)
    mean, var = variance_field(frames)
    fitted = camera_law(var, mean.mean(axis=-1))
    found, clean_found = encoded_clean(mean, var, fitted, 16, rng, encoding)
    # the dequantised clean image is nearer the truth than the seed mean
    assert np.abs(clean_found - clean).mean() < np.abs(mean - clean).mean()
    off = abs(np.log(fitted[0] / law[0]))
    assert off > np.log(2)  # the decoded law is off by 2x or more
    # about 0.2 DN: the level is found to within 60% (measured 1.54x), nearer than the
    # decoded law (2.1x); the errors of the seed mean's own flips bias it up
    assert abs(np.log(found[0] / law[0])) < min(np.log(1.6), off)


def test_the_shared_streams_check_fires_on_shared_noise_only(coloured_scene):
    """The calibration's shared-streams check is the audit's: frames whose right view repeats
    the left view's noise (one sampler seed for both) read far above the threshold, frames
    drawn independently about 0."""
    from stereovar.calibration.view_statistics import _shared_streams_row
    from stereovar.statistics.residuals import SHARED_STREAMS

    rng = np.random.default_rng(8)
    left = draw_frames(coloured_scene.mean["left"], 1e-3, 8, rng)
    noise = left - coloured_scene.mean["left"][None]
    shared = {"left": left, "right": (coloured_scene.mean["right"][None] + noise)
              .astype(np.float32)}
    apart = {"left": left, "right": draw_frames(coloured_scene.mean["right"], 1e-3, 8, rng)}
    row = _shared_streams_row(shared, coloured_scene, AnalysisSettings())
    assert row["boot_low"] > SHARED_STREAMS and row["rho"] > 0.5
    row = _shared_streams_row(apart, coloured_scene, AnalysisSettings())
    assert row["boot_low"] < SHARED_STREAMS and abs(row["rho"]) < 0.05


@pytest.fixture(scope="module")
def integer_scene(coloured_scene):
    """The coloured scene with its right view the left one 2 px over, exactly (an integer
    disparity, np.roll): corresponding pixels share their clean value to the last bit, so
    an 8-bit encoding's sawtooth in the variance is the same in both views."""
    left = coloured_scene.mean["left"]
    mean = {"left": left, "right": np.roll(left, 2, axis=1)}
    valid = np.ones((H, W), bool)
    valid[:, -2:] = False
    truth = {v: {"disparity": np.full((H, W), 2.0), "valid": valid} for v in mean}
    variance = {v: 0.02 * m.mean(axis=-1) + 1e-4 for v, m in mean.items()}
    return SceneFrames(mean, variance, truth, np.zeros((H, W), bool), 1, 8, "integer|spp8")


def test_a_denoised_8_bit_render_at_an_integer_disparity_is_no_cue(integer_scene, monkeypatch):
    """8-bit sRGB at 0.2 DN of noise (a denoised render as Kubric ships it), at an integer
    disparity: each pixel's variance is fixed by its seed mean's place between two codes,
    and that sawtooth is the same in both views. Knowing the encoding, the statistic is
    undefined there (the variance is the encoding's at nearly every pixel), so neither the
    verdict rule nor the matching-cue rule can fire; at 0.4 DN it is defined, and no
    replicate fires. Without the quantisation term the 0.2 DN frames read far above the
    smallest cue called."""
    from stereovar.controls import quantisation

    def run(pipelines=("srgb8_0.2",)):
        rows, _ = scene_calibration(
            integer_scene, transforms=["none"], settings=AnalysisSettings(), replicates=2,
            strength_factors=[], expensive_replicates=0, pipelines=pipelines,
            pipeline_replicates=3)
        rows = [{**r, "scene": "s"} for r in rows]
        table, _ = calibration_table(rows, methods=("partial", LIFT_METHOD))
        return rows, table

    rows, table = run()
    data = [r["rho"] for r in rows if (r["kind"], r["method"]) == ("srgb8_0.2", "partial")]
    assert len(data) == 3 and np.isnan(data).all()
    assert not [r for r in table if r["kind"] == "srgb8_0.2" and r["check"] != "coverage"]
    _, table = run(("srgb8_0.4",))
    for method, rule in (("partial", "above_null"), (LIFT_METHOD, "matching")):
        fired = next(r for r in table if (r["check"], r["rule"], r["scope"], r["method"],
                                          r["kind"])
                     == ("false_positive_rate", rule, "scene", method, "srgb8_0.4"))
        assert fired["n"] == 3 and fired["value"] == 0
    monkeypatch.setattr(quantisation, "quantisation_variance", lambda mean, encoding: None)
    rows_without, _ = run()

    def specific(rows):
        data = np.mean([r["rho"] for r in rows
                        if (r["kind"], r["method"]) == ("srgb8_0.2", "partial")])
        null = np.mean([r["rho"] for r in rows
                        if (r["kind"], r["method"]) == ("camera_srgb8_0.2", "partial")])
        return data - null

    assert specific(rows_without) > 3 * MIN_EFFECT


def test_quantisation_variance_is_eq1_of_frames_on_two_codes():
    """Brute force: frames of a 16-bit linear and an 8-bit sRGB encoding that take one or two
    neighbouring codes per channel; their Eq. 1 variance (population, averaged over
    channels) equals the variance the encoding implies at their seed mean."""
    from stereovar.calibration.pipelines import integer_roundtrip
    from stereovar.controls.quantisation import code_values, quantisation_variance

    rng = np.random.default_rng(4)
    for encoding in ({"bits": 8, "transfer": "srgb", "scale": 2.0},
                     {"bits": 16, "transfer": "linear", "scale": 1.0}):
        table = code_values(encoding["bits"], encoding["transfer"], encoding["scale"])
        k = rng.integers(1, table.size - 2, size=(30, 40, 3))
        upper = rng.random((8, 30, 40, 3)) < rng.random((30, 40, 3))
        frames = np.where(upper, table[k + 1], table[k]).astype(np.float32)
        assert np.array_equal(integer_roundtrip(frames, **encoding), frames)
        mean, variance = variance_field(frames)
        expected = quantisation_variance(mean, encoding)
        # the table holds the float32 values the frames hold: only the mean's float64
        # rounding is left
        assert np.allclose(expected, variance, rtol=1e-6, atol=0)
        # every frame on one code: no variance, none implied
        flat = np.broadcast_to(table[k][None], (8, 30, 40, 3)).astype(np.float32)
        assert np.all(quantisation_variance(variance_field(flat)[0], encoding) == 0)
