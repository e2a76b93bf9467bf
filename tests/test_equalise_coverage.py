"""Coverage of the Monte Carlo-specific difference interval through ``equalise``, by simulation.

The calibration holds the 95% interval of ``partial`` minus its matched null
(:func:`stereovar.calibration.nulls.difference_interval`) to a coverage of 95 +/- 2% of
replicates, the estimand being the mean over the same scene's other replicates
(:func:`stereovar.calibration.summary.calibration_table`). Here a small coloured scene with
dark pixels is drawn as the calibration draws it (a planted cue of strength 1, about what the
renders show, and the ``camera`` null; :mod:`stereovar.calibration.synthesis`), passed
through the transform as the transform job applies it
(:func:`stereovar.calibration.stacks.transform_stack`) and measured by the same
statistic rows; the coverage is read from the calibration table.

``none`` is the check that the simulation itself is sound: the same scene, draws and
bootstrap cover there. Through ``equalise`` the variance of the :math:`N` outputs is the
camera law at their own seed mean, which the intensity control reads, so ``partial``
correlates only what the control leaves (the per-channel floor at 0 of noisy dark seed
means, and numerical remainders), carried by a few pixels: the bootstrap's standard error
follows the value and under-covers (this scene: 71% [61, 79] of 100 replicates, 62% with the
control and interval of commit 2812d46; 76-84% over other scene seeds, darkness and strength 2;
``none`` 97% on the same scene). The statistic may instead be declared undefined there (the
control leaves it nothing to correlate); an interval it does give must cover.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

from stereovar.calibration.rates import COVERAGE_TARGET
from stereovar.calibration.scene_frames import SceneFrames
from stereovar.calibration.stacks import transform_stack
from stereovar.calibration.summary import calibration_table
from stereovar.calibration.synthesis import draw_frames, planted_pattern, variance_fields
from stereovar.calibration.view_statistics import statistic_rows
from stereovar.statistics.bootstrap import BootstrapSettings
from stereovar.statistics.fields import AnalysisSettings

H, W, D, N = 48, 64, 3, 8
LAW = (0.02, 1e-6)  # a*mu + b: shot noise with a small read-noise floor, as the renders' fit
PLANTED_REPLICATES = 100  # enough that 95% coverage is not shown short (Wilson) by chance
NULL_REPLICATES = 40
SETTINGS = AnalysisSettings(bootstrap=BootstrapSettings(tile=8))  # 48 tiles of 8 x 8


@pytest.fixture(scope="module")
def scene():
    """A coloured textured scene, the right view the left seen ``D`` px further right, with
    its darkest pixels (about 0.1%) dark enough that a channel of an 8-seed mean can fall
    below 0 under the planted cue."""
    rng = np.random.default_rng(3)
    texture = gaussian_filter(rng.normal(0.0, 1.0, (H, W)), 1.5)
    tint = np.exp(
        0.3 * np.stack([gaussian_filter(rng.normal(size=(H, W)), 4) for _ in range(3)], -1) / 0.07
    )
    mu = np.exp(1.2 * texture / texture.std() - 1.0)
    left = mu[..., None] * tint / tint.mean(axis=-1, keepdims=True)
    mean = {"left": left, "right": np.roll(left, D, axis=1)}
    truth = {v: {"disparity": np.full((H, W), float(D)), "valid": np.ones((H, W), bool)}
             for v in mean}
    return SceneFrames(mean, {}, truth, np.zeros((H, W), bool), 1, N, "coverage|spp8")


def coverage_row(scene, transform: str) -> tuple[dict | None, int]:
    """The calibration table's coverage row of the difference at the planted design (None
    when no replicate had an interval), and how many planted replicates had one."""
    gt = scene.ground_truth["right"]
    rows = []
    for r in range(max(PLANTED_REPLICATES, NULL_REPLICATES)):
        rng = np.random.default_rng([7, r])
        pattern = planted_pattern(gt["disparity"], gt["valid"], sign=scene.sign, rng=rng)
        for kind, strength, count in (("camera", 0.0, NULL_REPLICATES),
                                      ("planted", 1.0, PLANTED_REPLICATES)):
            if r >= count:
                continue
            v = variance_fields(kind, strength, mean=scene.mean, law=LAW, render_variance={},
                                pattern=pattern, rng=rng)
            stacks = {
                view: transform_stack(transform, draw_frames(scene.mean[view], v[view], N, rng),
                                      view=view, seed=r)
                for view in ("left", "right")
            }
            (row,) = statistic_rows(stacks, scene, SETTINGS, f"{r}|{kind}|{transform}",
                                    methods=("partial",))
            rows.append({"scene": "s", "replicate": r, "kind": kind, "strength": strength,
                         "strength_factor": 1.0 if strength else 0.0, "transform": transform,
                         **row})
    defined = sum(r["kind"] == "planted" and np.isfinite(r["rho"]) for r in rows)
    table, _ = calibration_table(rows, methods=("partial",))
    found = [t for t in table if t["check"] == "coverage" and t["rule"] == "difference"
             and t["scope"] == "scene" and t["kind"] == "planted"]
    return (found[0] if found else None), defined


@pytest.mark.parametrize(("transform", "may_be_undefined"), [("none", False), ("equalise", True)])
def test_difference_interval_covers_at_the_planted_cue(scene, transform, may_be_undefined):
    """Where the statistic is measured, its difference interval's coverage is not shown
    below 93%: the upper end of the coverage's 95% Wilson interval reaches it (the
    calibration table's ``meets_target`` is not ``short``). Through ``equalise`` the
    statistic may instead be undefined on every replicate (no interval, so no claim), never
    on some only."""
    row, defined = coverage_row(scene, transform)
    if may_be_undefined and defined == 0:
        assert row is None
        return
    assert defined == PLANTED_REPLICATES and row is not None and row["n"] == defined
    low_target = COVERAGE_TARGET[0]
    assert row["high"] >= low_target, (
        f"{transform}: the difference interval covered {row['value']:.0%} "
        f"[{row['low']:.0%}, {row['high']:.0%}] of {row['n']} planted replicates, "
        f"below the {low_target:.0%} the calibration holds it to"
    )
