"""The chance term of a Monte Carlo-specific difference (stereovar.statistics.chance), and the
difference interval it widens, on data whose answer is known."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

from stereovar.calibration.nulls import matched_nulls, with_differences
from stereovar.calibration.rates import Z
from stereovar.calibration.replicates import scene_calibration
from stereovar.calibration.scene_frames import SceneFrames
from stereovar.calibration.summary import calibration_table
from stereovar.calibration.synthesis import smooth_field
from stereovar.statistics.chance import chance_se
from stereovar.statistics.fields import AnalysisSettings

H, W = 96, 160


def _spread_and_se(draw, draws=80, seed=0):
    """The standard deviation of Pearson's rho over independent draws of a pair of fields,
    and the mean of :func:`chance_se` over the same draws (a region: all but a left band)."""
    rng = np.random.default_rng(seed)
    mask = np.ones((H, W), bool)
    mask[:, :20] = False
    index = np.flatnonzero(mask)
    rhos, ses = [], []
    for _ in range(draws):
        a, b = (f.ravel()[index] for f in draw(rng))
        rhos.append(np.corrcoef(a, b)[0, 1])
        ses.append(chance_se(a, b, index, (H, W)))
    return float(np.std(rhos, ddof=1)), float(np.mean(ses))


@pytest.mark.parametrize("scale", [2.0, 6.0])
def test_independent_structured_fields_spread_as_the_chance_term_says(scale):
    """Two independent fields smoothed over a few pixels: rho spreads far more than
    1/sqrt(n) (what a pixel-wise interval assumes), and as much as the chance term says."""
    def draw(rng):
        return [gaussian_filter(rng.standard_normal((H, W)), scale) for _ in range(2)]

    spread, se = _spread_and_se(draw)
    n = H * (W - 20)
    assert spread > 3 / np.sqrt(n)  # structure: well above white noise's spread
    assert se == pytest.approx(spread, rel=0.2)


def test_a_shared_pattern_under_white_noise_spreads_as_the_chance_term_says():
    """Correlated fields (a planted-like pattern shared by both, rho about 0.3): Bartlett's
    formula with the cross terms, not the independent one, gives the spread."""
    def draw(rng):
        z = smooth_field((H, W), rng)
        return [0.3 * z + 0.5 * rng.standard_normal((H, W)) for _ in range(2)]

    spread, se = _spread_and_se(draw)
    assert se == pytest.approx(spread, rel=0.2)


@pytest.fixture(scope="module")
def structured_scene():
    """A textured scene (right view 3 px to the right) whose renders' variance carries
    structure beyond the camera law, smooth over about 6 px, as a path tracer's does: the
    ``misaligned`` null then correlates by chance far more than the camera null spreads."""
    rng = np.random.default_rng(3)
    texture = gaussian_filter(rng.normal(0.0, 1.0, (64, 96)), 1.5)
    mu = np.exp(1.2 * texture / texture.std() - 1.0)
    left = np.repeat(mu[..., None], 3, axis=-1)
    mean = {"left": left, "right": np.roll(left, 3, axis=1)}
    truth = {v: {"disparity": np.full((64, 96), 3.0), "valid": np.ones((64, 96), bool)}
             for v in mean}
    variance = {
        v: (0.02 * m.mean(axis=-1) + 1e-4) * np.exp(smooth_field((64, 96), rng, scale=6.0))
        for v, m in mean.items()
    }
    return SceneFrames(mean, variance, truth, np.zeros((64, 96), bool), 1, 8, "structured|spp8")


def test_the_camera_nulls_difference_interval_is_as_wide_as_its_spread(structured_scene):
    """The defect: the chance correlation of the unaligned renders (their ``misaligned``
    spread) was added to every difference interval, so the camera null's covered 100% and
    power was lost. Now each interval is as wide as its own fields allow: camera noise is
    white, so its half-width over z is about :math:`1/\\sqrt n`, the spread of a
    correlation of independent white fields, within the 40 replicates' estimation (whose
    own spread the test also bounds); the unaligned renders spread several times more."""
    rows, _ = scene_calibration(
        structured_scene, transforms=["none"], settings=AnalysisSettings(), replicates=40,
        strength_factors=[1.0], expensive_replicates=0,
    )
    chosen = [
        {**r, "scene": "s", **{k: float(r[k]) for k in ("rho", "boot_low", "boot_high")}}
        for r in rows if r["method"] == "partial" and r["region"] == "all"
    ]
    diffs = [d for d in with_differences(chosen, matched_nulls(chosen)) if d["kind"] == "camera"]
    spread = np.std([d["diff"] for d in diffs], ddof=1)
    half = np.mean([(d["diff_high"] - d["diff_low"]) / 2 for d in diffs]) / Z
    white = 1 / np.sqrt(int(chosen[0]["n_pixels"]))
    misaligned = np.std([float(r["rho"]) for r in chosen if r["kind"] == "misaligned"], ddof=1)
    assert half == pytest.approx(white, rel=0.2)
    assert 0.7 * white < spread < 1.3 * white  # 40 replicates: +/- 22% at 95%
    assert misaligned > 2.5 * half  # the old chance term would have dwarfed the interval


def test_the_misaligned_null_is_covered_by_its_own_chance_term(structured_scene):
    """Unaligned render-like fields: the chance term of each replicate follows the fields'
    structure, so the rule above the null fires on none of them."""
    scene = dataclasses.replace(structured_scene, label="structured-2|spp8")
    rows, _ = scene_calibration(
        scene, transforms=["none"], settings=AnalysisSettings(), replicates=12,
        strength_factors=[1.0], expensive_replicates=0,
    )
    table, _ = calibration_table([{**r, "scene": "s"} for r in rows], methods=("partial",))
    fp = next(r for r in table if (r["check"], r["rule"], r["scope"], r["kind"])
              == ("false_positive_rate", "above_null", "scene", "misaligned"))
    assert fp["value"] == 0.0
    chance = [float(r["chance_se"]) for r in rows
              if r["kind"] == "misaligned" and r["method"] == "partial"]
    boot = [(float(r["boot_high"]) - float(r["boot_low"])) / (2 * Z) for r in rows
            if r["kind"] == "misaligned" and r["method"] == "partial"]
    assert np.mean(chance) > np.mean(boot)  # the structure the bootstrap's tiles miss
