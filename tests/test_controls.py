"""Controls: the sensor baseline, the intensity control, the null warps and the claims
verdicts, against brute-force or analytic references."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from stereovar.controls.intensity import intensity_residuals, relative_variance
from stereovar.controls.null_warps import flipped_warp, shifted_warp
from stereovar.controls.partial import partial_pair
from stereovar.controls.sensor import (
    SensorFrames,
    SensorModel,
    sensor_variance,
    simulated_sensor_variance,
)
from stereovar.statistics.claim_rules import (
    EXPLAINED,
    FAILS,
    HOLDS,
    UNTESTABLE,
    verdict,
)
from stereovar.statistics.claims import claims_table
from stereovar.statistics.fields import AnalysisSettings
from stereovar.statistics.rows import SceneInputs, correlation_rows
from stereovar.statistics.warp import align_variance


def test_analytic_sensor_variance_matches_many_simulated_frames():
    rng = np.random.default_rng(0)
    mu = rng.uniform(0.01, 2.0, size=(12, 15, 3))
    mu[0, 0, 0] = -0.5  # floored and counted
    model = SensorModel(gain=200.0, read_noise=3.0)
    want, floored = sensor_variance(mu, model)
    assert floored == 1
    frames = np.stack(list(SensorFrames(mu, 4000, model, seed=1)))
    brute = frames.var(axis=0).mean(axis=-1)
    rel = np.abs(brute - want) / want
    assert rel.mean() < 0.02 and rel.max() < 0.1
    # the formula by hand: mean over channels of mu/g + (r/g)^2, mu floored at 0
    clean = np.maximum(mu, 0)
    np.testing.assert_allclose(want, (clean / 200.0 + (3.0 / 200.0) ** 2).mean(-1))


def test_one_step_eq1_draw_has_the_law_of_eq1_over_simulated_frames():
    """Eq. 1 of N = 8 Poisson-Gaussian frames, repeated 3000 times by brute force, against
    the gamma draw's mean and variance, per pixel and channel (dim, mid and bright)."""
    from stereovar.controls.sensor import eq1_moments
    from stereovar.estimators.seeds import variance_field

    mu = np.array([0.002, 0.02, 0.5, 2.0]).reshape(1, 4, 1) * np.ones((1, 1, 3))
    model = SensorModel(gain=1000.0, read_noise=2.0)
    n, reps = 8, 3000
    frames = np.stack(list(SensorFrames(mu, n * reps, model, seed=3)))
    per_rep = frames.reshape(reps, n, *mu.shape)
    s2 = per_rep.var(axis=1)  # Eq. 1 per channel, population variance
    mean, variance = eq1_moments(mu, n, model)
    np.testing.assert_allclose(s2.mean(axis=0), mean, rtol=0.05)
    np.testing.assert_allclose(s2.var(axis=0), variance, rtol=0.15)
    # Eq. 1 as the project computes it, on one set of frames
    _, eq1 = variance_field(per_rep[0])
    np.testing.assert_allclose(eq1, s2[0].mean(axis=-1), rtol=1e-6)
    # the one-step draws: same mean and spread of the channel-averaged field
    draws = np.stack([simulated_sensor_variance(mu, n, model, seed=(k,)) for k in range(3000)])
    brute = s2.mean(axis=-1)
    np.testing.assert_allclose(draws.mean(axis=0), brute.mean(axis=0), rtol=0.05)
    np.testing.assert_allclose(draws.std(axis=0), brute.std(axis=0), rtol=0.1)


def test_sensor_frames_are_reproducible_and_views_independent():
    mu = np.full((4, 5, 3), 0.5)
    model = SensorModel()
    a = SensorFrames(mu, 3, model, seed=(0, 1))
    np.testing.assert_array_equal(a[2], SensorFrames(mu, 3, model, seed=(0, 1))[2])
    assert not np.array_equal(a[0], SensorFrames(mu, 3, model, seed=(0, 2))[0])
    assert len(a) == 3 and len(a[0:2]) == 2
    with pytest.raises(ValueError, match="gain"):
        SensorModel(gain=0)


def test_partial_correlation_matches_lstsq_residuals():
    """Residual correlation is 0.5 by construction once the intensity relation is removed.

    The control's spline space holds every cubic, so its residuals are least-squares residuals
    orthogonal to 1, ln mu, ..., (ln mu)^3; with one knot interval they are the cubic's."""
    rng = np.random.default_rng(1)
    n = 20000
    log_mu = rng.uniform(-3, 1, size=n)
    shared = rng.normal(size=n)
    e_l = 0.5 * (math.sqrt(0.5) * shared + math.sqrt(0.5) * rng.normal(size=n)) * 2
    e_r = 0.5 * (math.sqrt(0.5) * shared + math.sqrt(0.5) * rng.normal(size=n)) * 2
    log_var_l = 0.3 * log_mu**3 - log_mu + 2 + e_l
    log_var_r = 0.2 * log_mu**2 + 0.9 * log_mu + e_r
    mu = np.exp(log_mu)
    ra, rb = partial_pair(np.exp(log_var_l), np.exp(log_var_r), mu, mu)
    design = np.vander(log_mu, 4)
    for got, y, e in ((ra, log_var_l, e_l), (rb, log_var_r, e_r)):
        beta, *_ = np.linalg.lstsq(design, y, rcond=None)
        cubic = y - design @ beta
        scale = np.linalg.norm(design, axis=0) * np.linalg.norm(got)
        assert np.all(np.abs(design.T @ got) < 1e-9 * scale)  # orthogonal to every cubic
        assert np.linalg.norm(got - e) < 0.05 * np.linalg.norm(e)  # the relation, removed
        np.testing.assert_allclose(intensity_residuals(y, log_mu, intervals=1), cubic, atol=1e-8)
    assert stats.pearsonr(ra, rb)[0] == pytest.approx(0.5, abs=0.03)
    # the raw logs are dominated by intensity: far from 0.5
    assert abs(stats.pearsonr(log_var_l, log_var_r)[0] - 0.5) > 0.1
    assert np.isnan(intensity_residuals(np.ones(3), np.ones(3))).all()
    assert relative_variance(np.array([4.0, 1.0]), np.array([2.0, 0.0]))[0] == 1.0


def _pair(shape, d, left, right):
    gt = {
        "disparity": np.full(shape, float(d)),
        "valid": np.ones(shape, bool),
        "glass": np.zeros(shape, bool),
    }
    aligned = align_variance(left, right, gt, sign=1)
    return gt, aligned


def test_null_warps_are_about_zero_on_independent_fields():
    rng = np.random.default_rng(2)
    shape, d = (120, 160), 4
    left, right = rng.lognormal(size=(2, *shape))
    gt, aligned = _pair(shape, d, left, right)
    rows = correlation_rows(
        left, right, aligned, gt["glass"], inputs=SceneInputs(ground_truth_left=gt, sign=1)
    )
    by = {(r["region"], r["method"]): r for r in rows}
    for method in ("null_shift", "null_flip", "warp"):
        assert abs(by["all", method]["rho"]) < 0.03
        assert by["all", method]["boot_low"] < 0 < by["all", method]["boot_high"]


def test_shifted_warp_changes_nothing_on_a_field_constant_along_x():
    rng = np.random.default_rng(3)
    shape, d = (80, 100), 3
    profile = rng.lognormal(size=(shape[0], 1))
    left = np.broadcast_to(profile, shape) * rng.lognormal(sigma=0.1, size=shape)
    right = np.broadcast_to(profile, shape).copy()
    gt, aligned = _pair(shape, d, left, right)
    settings = AnalysisSettings(null_shift=8)
    rows = correlation_rows(
        left,
        right,
        aligned,
        gt["glass"],
        settings=settings,
        inputs=SceneInputs(ground_truth_left=gt, sign=1),
    )
    by = {(r["region"], r["method"]): r for r in rows}
    # same values on the pixels both keep: the shifted warp drops the last 8 columns too
    shifted = shifted_warp(right, gt["disparity"], 8, sign=1)
    keep = np.isfinite(shifted) & aligned["omega"]
    np.testing.assert_allclose(shifted[keep], aligned["warped"][keep])
    assert by["all", "null_shift"]["rho"] == pytest.approx(
        stats.pearsonr(left[keep], shifted[keep])[0], abs=1e-12
    )
    assert by["all", "null_shift"]["rho"] == pytest.approx(by["all", "warp"]["rho"], abs=0.02)
    flipped = flipped_warp(right, gt["disparity"], sign=1)
    np.testing.assert_allclose(flipped[:, 0], right[::-1, d])


def test_sensor_and_intensity_rows_from_a_seed_mean():
    rng = np.random.default_rng(4)
    shape, d = (60, 90), 2
    mu_l = rng.uniform(0.05, 1.0, size=(*shape, 3))
    mu_r = np.zeros_like(mu_l)
    mu_r[:, d:] = mu_l[:, :-d]
    left = mu_l.mean(-1) * rng.lognormal(sigma=0.2, size=shape)
    right = mu_r.mean(-1) * rng.lognormal(sigma=0.2, size=shape)
    gt, aligned = _pair(shape, d, left, right)
    rows = correlation_rows(
        left,
        right,
        aligned,
        gt["glass"],
        inputs=SceneInputs(
            ground_truth_left=gt,
            sign=1,
            mean={"left": mu_l, "right": mu_r},
            n_seeds=8,
            sensor=SensorModel(),
            label="synthetic",
        ),
    )
    by = {(r["region"], r["method"]): r for r in rows}
    # the analytic sensor field is linear in the shared intensity: rho = 1
    assert by["all", "sensor"]["rho"] == pytest.approx(1.0, abs=1e-9)
    # N = 8 simulated frames: far below 1, far above 0
    assert 0.2 < by["all", "sensor_sim"]["rho"] < 0.95
    # the variance here is intensity times independent noise: nothing left once it is removed
    assert abs(by["all", "partial"]["rho"]) < 0.05
    assert by["all", "warp"]["rho"] > 0.5


def test_each_verdict_from_synthetic_inputs():
    nan3 = (math.nan,) * 3
    assert verdict("level", 0.75, 0.7, 0.6, 0.8, (0.1, 0.0, 0.2)) == HOLDS
    assert verdict("level", 0.75, 0.4, 0.35, 0.45) == FAILS
    assert verdict("level", 0.75, 0.7, 0.6, 0.8, (0.65, 0.55, 0.7)) == EXPLAINED
    assert verdict("level", 0.75, math.nan, math.nan, math.nan) == UNTESTABLE
    # an interval holding the paper's value and the null (rho 0) cannot tell them apart
    assert verdict("level", 0.75, 0.4, -0.1, 0.9) == UNTESTABLE
    assert verdict("direction", -0.4, -0.3, -0.5, -0.1) == HOLDS
    assert verdict("direction", -0.4, 0.3, 0.1, 0.5) == FAILS
    assert verdict("direction", -0.4, -0.3, -0.6, 0.1) == UNTESTABLE
    assert verdict("direction", -0.4, -0.3, -0.5, -0.1, (-0.2, -0.3, -0.1)) == EXPLAINED
    assert verdict("tolerance", 0.002, 0.001, 0.0005, 0.0015) == HOLDS
    assert verdict("tolerance", 0.002, 0.05, 0.04, 0.06) == FAILS
    assert verdict("tolerance", 0.002, math.nan, *nan3[:2]) == UNTESTABLE


def _scene_rows(scene, rho_all, glass, sensor):
    rows = []
    for region, rho in (("all", rho_all), ("non_glass", rho_all), ("glass", glass)):
        for method, value in (("warp", rho), ("sensor_sim", sensor), ("spearman", rho)):
            rows.append(
                {
                    "scene": scene,
                    "spp": 8,
                    "n_seeds": 8,
                    "region": region,
                    "method": method,
                    "rho": value,
                    "boot_low": value - 0.02,
                    "boot_high": value + 0.02,
                    "rho_corrected": value,
                    "mean_a": 7.0 if region == "glass" else 1.0,
                }
            )
    return rows


def test_claims_table_gives_the_verdict_the_inputs_imply():
    rows = _scene_rows("a", 0.754, 0.301, 0.0) + _scene_rows("b", 0.754, 0.301, 0.0)
    sweep = [{"spp": 8, "rho_all": 0.754}, {"spp": 16, "rho_all": 0.7545}]
    claims = {c["claim"]: c for c in claims_table(rows, sweep=sweep)}
    assert claims["rho (all) = 0.754"]["verdict"] == HOLDS
    assert claims["rho (glass) = 0.301"]["verdict"] == HOLDS
    assert claims["rho glass below non-glass (0.301 - 0.779)"]["verdict"] == HOLDS
    # a spread over the sweep has no interval, so equivalence within 0.2% cannot be shown
    assert claims["rho invariant to SPP within 0.2%"]["verdict"] == UNTESTABLE
    # sensor rho 0 in both scenes: the scenes agree, so the 90% interval over scenes is
    # [0, 0], inside the claim's margin of 0.1
    assert claims["real sensors carry rho = 0"]["verdict"] == HOLDS
    assert claims["glass variance 7x non-glass"]["ours"] == pytest.approx(7.0)
    assert claims["glass variance 7x non-glass"]["verdict"] == HOLDS
    assert claims["no-warp rho = 0.36"]["verdict"] == UNTESTABLE
    # a sensor that reaches the same level explains the headline away
    rows = _scene_rows("a", 0.754, 0.301, 0.75) + _scene_rows("b", 0.754, 0.301, 0.75)
    claims = {c["claim"]: c for c in claims_table(rows)}
    assert claims["rho (all) = 0.754"]["verdict"] == EXPLAINED
    assert claims["real sensors carry rho = 0"]["verdict"] == FAILS
    assert claims["rho invariant to SPP within 0.2%"]["verdict"] == UNTESTABLE


def test_covariate_columns_by_blocks_equal_the_joined_matrix():
    """The control's candidate columns stay in blocks (chromaticity, position,
    quantisation); their products, their Gram matrix and any selection equal those of the
    joined matrix, built here column by column from the Legendre polynomials."""
    from numpy.polynomial import legendre

    from stereovar.controls.covariates import design

    rng = np.random.default_rng(3)
    n = 500
    colour = (rng.uniform(0.5, 1.5, n), rng.uniform(0.5, 1.5, n))
    position = (rng.uniform(0, 63, n), rng.uniform(0, 31, n))
    q = np.where(rng.random(n) < 0.2, 0.0, rng.uniform(1e-6, 1e-4, n))
    columns, degrees, gram = design(colour, position, q, colour_degree=2, position_degree=2)

    def unit(v):
        return (2 * v - (v.min() + v.max())) / (v.max() - v.min())

    def total(u, v, d):
        return [legendre.legval(u, np.eye(d + 1)[i]) * legendre.legval(v, np.eye(d + 1)[t - i])
                for t in range(1, d + 1) for i in range(t + 1)]

    logs = np.log(np.where(q > 0, q, q[q > 0].min()))
    joined = np.column_stack(
        total(unit(colour[0]), unit(colour[1]), 2) + total(unit(position[0]), unit(position[1]), 2)
        + [(q <= 0).astype(float)] + [legendre.legval(unit(logs), np.eye(4)[k]) for k in (1, 2, 3)])
    joined -= joined.mean(axis=0)
    assert columns.shape == joined.shape == (n, 5 + 5 + 4)
    assert degrees.tolist() == [[1, 1, 2, 2, 2] + [0] * 9, [0] * 5 + [1, 1, 2, 2, 2] + [0] * 4,
                                [0] * 10 + [1, 1, 2, 3]]
    np.testing.assert_allclose(gram, joined.T @ joined, rtol=1e-10, atol=1e-9)
    y, beta = rng.normal(size=n), rng.normal(size=14)
    np.testing.assert_allclose(columns.rmatvec(y), joined.T @ y, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(columns.matvec(beta), joined @ beta, rtol=1e-10, atol=1e-10)
    for use in (np.r_[0:2, 5:8], np.r_[1, 3, 9, 10, 12]):  # leading columns, then any
        part = columns.take(use)
        np.testing.assert_allclose(part.matvec(beta[use]), joined[:, use] @ beta[use],
                                   rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(part.rmatvec(y), joined[:, use].T @ y, rtol=1e-10, atol=1e-10)
