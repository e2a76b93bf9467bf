"""Intervals of correlations across scenes stay inside [-1, 1]: the combined and the
random-effects intervals placed on Fisher's z (stereovar.statistics.across), and their
callers (the claims table, the audit's summaries, the calibration's combined rows, the
attenuation-corrected rho).

Every expected value is computed here from the inputs with numpy and scipy (normal and
Student-t quantiles, atanh and tanh), not read back from the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, stats

from stereovar.statistics.across import (
    combined_correlation_interval,
    combined_interval,
    random_effects_correlation_interval,
    random_effects_interval,
)

Z = stats.norm.ppf(0.975)


def on_fisher_z(mean, half):
    """The interval of a correlation with the normal interval ``mean +- half``'s length,
    placed symmetric on Fisher's z about ``atanh(mean)``: solved numerically here (the
    library solves it in closed form); all of [-1, 1] when ``half >= 1``."""
    if half >= 1:
        return -1.0, 1.0
    centre = math.atanh(mean)

    def excess(a):
        return math.tanh(centre + a) - math.tanh(centre - a) - 2 * half

    a = optimize.brentq(excess, 0.0, 60.0, xtol=1e-15, rtol=1e-15)
    return math.tanh(centre - a), math.tanh(centre + a)


def normal_interval(rhos, halves):
    """The scenes' intervals ``rho +- half`` combined as independent normal errors, by
    hand: the mean and its half-width."""
    rhos, halves = np.asarray(rhos, float), np.broadcast_to(np.asarray(halves, float), len(rhos))
    se = halves / Z
    return rhos.mean(), Z * math.sqrt(float((se**2).sum())) / rhos.size


# ------------------------------------------------------------- (a) analytic cases


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_combined_interval_near_one_stays_inside_and_keeps_the_normal_length(sign):
    rhos = sign * np.array([0.97, 0.985, 0.995])
    halves = np.array([0.04, 0.03, 0.02])
    mean, half = normal_interval(rhos, halves)
    assert abs(mean) + half > 1  # the normal-scale interval passes the bound
    normal = combined_interval(rhos, rhos - halves, rhos + halves)
    assert normal[1:] == pytest.approx((mean - half, mean + half), rel=1e-12)
    got, low, high = combined_correlation_interval(rhos, rhos - halves, rhos + halves)
    assert got == pytest.approx(mean, rel=1e-12)  # the point estimate does not move
    assert -1 < low < got < high < 1
    # symmetric on Fisher's z about the mean's z, with the normal interval's length
    assert math.atanh(low) + math.atanh(high) == pytest.approx(2 * math.atanh(mean), rel=1e-9)
    assert high - low == pytest.approx(2 * half, rel=1e-9)
    assert (low, high) == pytest.approx(on_fisher_z(mean, half), rel=1e-9)
    # it slides away from the bound: shorter on the side of the bound
    toward, away = (high - got, got - low) if sign > 0 else (got - low, high - got)
    assert toward < half < away


def test_a_combined_interval_far_from_one_is_the_normal_one_to_first_order():
    rhos = np.array([0.28, 0.30, 0.32])
    halves = np.array([0.012, 0.010, 0.008])
    mean, half = normal_interval(rhos, halves)
    _, low, high = combined_correlation_interval(rhos, rhos - halves, rhos + halves)
    # the delta method: half-width on z = half-width on rho / (1 - rho^2), to first order
    half_z = (math.atanh(high) - math.atanh(low)) / 2
    assert half_z == pytest.approx(half / (1 - mean**2), rel=1e-3)
    # and the bounds are the normal bounds up to a second-order shift (half^2 scale)
    assert abs(low - (mean - half)) < half**2
    assert abs(high - (mean + half)) < half**2


def test_a_combined_interval_of_a_scene_whose_bound_is_one():
    """A bootstrap bound at exactly 1 (no Fisher z) still counts with its width."""
    rhos, lows, highs = [0.99, 0.999], [0.9, 0.99], [1.0, 1.0]
    mean, half = 0.9945, Z * math.hypot(0.1 / (2 * Z), 0.01 / (2 * Z)) / 2
    got, low, high = combined_correlation_interval(rhos, lows, highs)
    assert got == pytest.approx(mean)
    assert -1 < low < mean < high < 1
    assert (low, high) == pytest.approx(on_fisher_z(mean, half), rel=1e-9)


def test_a_combined_interval_as_long_as_the_range_is_the_range():
    """One scene whose interval is all of [-1, 1] (or, from bounds past it, longer): the
    interval of that length placed on z is [-1, 1]."""
    assert combined_correlation_interval([0.0], [-1.0], [1.0]) == pytest.approx((0, -1, 1))
    assert combined_correlation_interval([0.3], [-1.5], [1.5]) == (0.3, -1.0, 1.0)
    # two such scenes: the mean's normal interval has length 2 / sqrt(2), inside the range
    got, low, high = combined_correlation_interval([0.0, 0.1], [-1.0, -1.0], [1.0, 1.0])
    assert -1 < low < got < high < 1 and high - low == pytest.approx(2 / math.sqrt(2))


def test_combined_correlation_interval_leaves_out_non_finite_scenes_and_refuses_non_correlations():
    got = combined_correlation_interval([0.5, math.nan, 0.6], [0.4, 0.1, math.nan], [0.6, 0.9, 0.7])
    assert got == combined_correlation_interval([0.5], [0.4], [0.6])
    assert all(math.isnan(v) for v in combined_correlation_interval([math.nan], [0.1], [0.2]))
    with pytest.raises(ValueError, match=r"\[-1, 1\]"):
        combined_correlation_interval([1.2, 0.5], [1.1, 0.4], [1.3, 0.6])
    # a difference of two correlations keeps the normal interval
    assert combined_interval([1.2], [1.1], [1.3]) == pytest.approx((1.2, 1.1, 1.3))


def test_a_random_effects_interval_far_from_one_is_the_t_interval_to_first_order():
    values = np.array([0.29, 0.30, 0.31, 0.30, 0.305])
    t = stats.t.ppf(0.975, values.size - 1)
    half = t * values.std(ddof=1) / math.sqrt(values.size)
    got, low, high = random_effects_correlation_interval(values)
    assert got == pytest.approx(values.mean(), rel=1e-12)
    half_z = (math.atanh(high) - math.atanh(low)) / 2
    assert half_z == pytest.approx(half / (1 - values.mean() ** 2), rel=1e-3)
    assert abs(low - (values.mean() - half)) < half**2
    # the 90% interval of the equivalence tests, by the same construction
    z = np.arctanh(values)
    h90 = stats.t.ppf(0.95, values.size - 1) * z.std(ddof=1) / math.sqrt(values.size)
    want = (math.tanh(math.atanh(values.mean()) - h90), math.tanh(math.atanh(values.mean()) + h90))
    assert random_effects_correlation_interval(values, level=0.90)[1:] == pytest.approx(want)
    # scenes that agree: the interval is their value, exactly (no round-off through z)
    assert random_effects_correlation_interval([0.301, 0.301]) == (0.301, 0.301, 0.301)
    assert combined_correlation_interval([0.301], [0.301], [0.301]) == (0.301, 0.301, 0.301)
    # one scene: no interval; none: NaN
    one = random_effects_correlation_interval([0.7, math.nan])
    assert one[0] == 0.7 and math.isnan(one[1]) and math.isnan(one[2])
    assert all(math.isnan(v) for v in random_effects_correlation_interval([]))


# ------------------------------------------------------------- (b) simulation


def test_b_combined_interval_covers_a_known_correlation_in_95_percent_of_runs():
    """2000 runs of S = 4 scenes, each 200 pixels of a bivariate normal with correlation
    0.9: each scene's Pearson r with its Fisher interval tanh(atanh r +- 1.96 / sqrt(n - 3)),
    combined. The interval should hold 0.9 in 95 +- 2% of runs (4 binomial standard errors
    of 0.0049 at 2000 runs): 94.75% with this seed (the normal-scale interval: 95.05%)."""
    rng = np.random.default_rng(7)
    runs, scenes, n, rho = 2000, 4, 200, 0.9
    x = rng.standard_normal((runs, scenes, n))
    y = rho * x + math.sqrt(1 - rho**2) * rng.standard_normal((runs, scenes, n))
    xc = x - x.mean(-1, keepdims=True)
    yc = y - y.mean(-1, keepdims=True)
    r = (xc * yc).sum(-1) / np.sqrt((xc * xc).sum(-1) * (yc * yc).sum(-1))
    half_z = Z / math.sqrt(n - 3)
    lows, highs = np.tanh(np.arctanh(r) - half_z), np.tanh(np.arctanh(r) + half_z)
    hits = 0
    for rr, lo, hi in zip(r, lows, highs, strict=True):
        _, low, high = combined_correlation_interval(rr, lo, hi)
        assert -1 < low <= high < 1
        hits += low <= rho <= high
    coverage = hits / runs
    assert 0.93 <= coverage <= 0.97, coverage


# ------------------------------------------------------------- (c) the claims table


def test_c_claims_random_effects_interval_of_a_mean_rho_stays_below_one():
    from stereovar.statistics.claims import claims_table

    values = np.array([0.95, 0.85, 0.20, 0.14])
    t = stats.t.ppf(0.975, values.size - 1)
    normal_high = values.mean() + t * values.std(ddof=1) / math.sqrt(values.size)
    assert normal_high > 1  # the normal-scale random-effects interval passes 1
    assert random_effects_interval(values)[2] == pytest.approx(normal_high)
    # by hand: Student-t over the scenes' z, about the mean rho's z, mapped back
    half = t * np.arctanh(values).std(ddof=1) / math.sqrt(values.size)
    centre = math.atanh(values.mean())
    want = (values.mean(), math.tanh(centre - half), math.tanh(centre + half))
    assert random_effects_correlation_interval(values) == pytest.approx(want, rel=1e-12)
    rows = [
        {"scene": f"s{s}", "region": "all", "method": "warp", "rho": float(r),
         "boot_low": float(r) - 0.02, "boot_high": float(r) + 0.02}
        for s, r in enumerate(values)
    ]  # fmt: skip
    row = {c["id"]: c for c in claims_table(rows)}["rho_all"]
    assert (row["ours"], row["ours_low"], row["ours_high"]) == pytest.approx(want, rel=1e-12)
    assert -1 < row["ours_low"] < row["ours_high"] < 1


def test_c_claims_difference_of_two_rho_keeps_the_normal_interval():
    """A difference of two correlations lies in [-2, 2]: its interval stays the Student-t
    interval of the per-scene differences."""
    from stereovar.statistics.claim_statistics import STATISTICS, ClaimInputs

    glass, non_glass = [0.9, 0.8, 0.95, 0.7], [0.1, 0.3, -0.2, 0.25]
    rows = [
        {"scene": f"s{s}", "region": region, "method": "warp", "rho": r}
        for region, rs in (("glass", glass), ("non_glass", non_glass))
        for s, r in enumerate(rs)
    ]
    diffs = np.subtract(glass, non_glass)
    want = stats.t.interval(0.95, 3, loc=diffs.mean(), scale=stats.sem(diffs))
    inputs = ClaimInputs(rows=rows, sweep=[], curve=[], intervention=[])
    got = STATISTICS["rho_difference"].compute(
        inputs, region="glass", minus="non_glass", method="warp"
    )
    assert (got.value, got.low, got.high) == pytest.approx((diffs.mean(), *want), rel=1e-12)


# ------------------------------------------------------------- the other callers


def test_corrected_interval_is_cut_to_minus_one_one():
    from stereovar.statistics.reliability import corrected_interval

    row = {"rho": 0.9, "boot_low": 0.85, "boot_high": 0.97, "reliability_left": 0.92,
           "reliability_right": 0.9, "rho_corrected": 0.9 / math.sqrt(0.92 * 0.9)}  # fmt: skip
    k = math.sqrt(0.92 * 0.9)
    assert corrected_interval(row, bounded=False) == pytest.approx((0.85 / k, 0.97 / k))
    assert 0.97 / k > 1
    assert corrected_interval(row) == pytest.approx((0.85 / k, 1.0))
    above = {**row, "boot_low": 0.93}
    assert corrected_interval(above) == pytest.approx((1.0, 1.0))  # wholly above 1
    assert all(math.isnan(v) for v in corrected_interval({**row, "reliability_left": 0.0}))


def test_audit_summaries_of_correlations_stay_inside_minus_one_one():
    from stereovar.audit.seeding import seeding_summary
    from stereovar.audit.verdict import correlation_summary

    rhos, lows = [0.95, 0.98], [0.85, 0.90]
    rows = [
        {"scene": f"f{i}", "region": "all", "method": "sensor", "rho": r,
         "boot_low": lo, "boot_high": 1.0}
        for i, (r, lo) in enumerate(zip(rhos, lows, strict=True))
    ]  # fmt: skip
    mean, low, high = correlation_summary(rows, "sensor", "all")
    normal = combined_interval(
        rhos, [r["boot_low"] for r in rows], [r["boot_high"] for r in rows]
    )
    assert normal[2] > 1 and mean == pytest.approx(np.mean(rhos))
    assert -1 < low < mean < high < 1 and high - low == pytest.approx(normal[2] - normal[1])
    # attenuation-corrected: combined on the normal scale from the uncut intervals, then cut
    k = math.sqrt(0.95 * 0.9)
    corrected = [
        {**r, "method": "warp", "reliability_left": 0.95, "reliability_right": 0.9,
         "rho_corrected": r["rho"] / k}
        for r in rows
    ]  # fmt: skip
    mean, low, high = correlation_summary(corrected, "corrected", "all")
    c_mean, c_half = normal_interval(
        [r / k for r in rhos], [(r["boot_high"] - r["boot_low"]) / (2 * k) for r in rows]
    )
    assert mean == pytest.approx(c_mean)  # above 1 as a point estimate: flagged elsewhere
    assert c_mean - c_half < 1 < c_mean + c_half
    assert (low, high) == pytest.approx((c_mean - c_half, 1.0))
    # the residual correlation of the seeding check
    seeding = [
        {"alignment": "zero", "region": "all", "rho": r, "low": lo, "high": 1.0}
        for r, lo in zip(rhos, lows, strict=True)
    ]
    mean, low, high = seeding_summary(seeding, "zero")
    assert -1 < low < mean < high < 1


def test_calibration_combined_rows_bound_rho_and_keep_differences_normal():
    from stereovar.calibration.nulls import combined_rows

    base = {"replicate": 0, "kind": "camera", "strength_factor": 1.0, "transform": "none",
            "region": "all", "method": "partial"}  # fmt: skip
    rows = [
        {**base, "scene": s, "rho": r, "boot_low": r - 0.04, "boot_high": min(r + 0.04, 1.0),
         "diff": d, "diff_low": d - 0.3, "diff_high": d + 0.3}
        for s, r, d in (("a", 0.97, 0.9), ("b", 0.99, 1.2))
    ]  # fmt: skip
    (row,) = combined_rows(rows)
    assert -1 < row["boot_low"] < row["rho"] < row["boot_high"] < 1
    d_mean, d_half = normal_interval([0.9, 1.2], 0.3)
    assert (row["diff"], row["diff_low"], row["diff_high"]) == pytest.approx(
        (d_mean, d_mean - d_half, d_mean + d_half)
    )
    assert row["diff_high"] > 1  # a difference is not bounded by 1
