"""Bootstrap intervals, robust statistics, split-half reliability and the seed subsets,
against brute-force or analytic references."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage, stats

from stereovar.estimators.seeds import StreamingVariance
from stereovar.estimators.subsets import SeedSubsets, pooled_moments, subset_dataset
from stereovar.statistics.bootstrap import (
    FEWER_THAN_2_TILES,
    BootstrapSettings,
    bootstrap_replicates,
    draw_counts,
    percentile_interval,
    tile_labels,
    tile_sums,
)
from stereovar.statistics.fields import AnalysisSettings
from stereovar.statistics.registry import METHODS, BootstrapDraws, evaluate
from stereovar.statistics.reliability import attenuation_corrected, spearman_brown
from stereovar.statistics.robust import firefly_count, log_floor, top_share, trim_mask

from .reference.correlation import correlation_rows


def _fields(a, b):
    from stereovar.statistics.fields import AlignedFields

    return AlignedFields(a, b, b)


def _boot(a, b, tile, reps=2000, seed=1):
    settings = AnalysisSettings(min_pixels=30, bootstrap=BootstrapSettings(tile, reps, seed))
    mask = np.ones(a.shape, bool)
    return evaluate(
        METHODS.get("warp"),
        _fields(a, b),
        mask,
        settings=settings,
        labels=tile_labels(a.shape, tile),
        draws=BootstrapDraws(settings.bootstrap, seed),
    )


def test_tile_sums_match_a_loop_over_tiles():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(2, 37, 50))
    labels = tile_labels(a.shape, 16)
    sums = tile_sums(a.ravel(), b.ravel(), labels.ravel())
    assert sums.shape == (3 * 4, 6)
    # Pearson of the summed statistics is Pearson of the pixels (centring and scaling aside).
    rho = bootstrap_replicates(sums, np.ones((1, sums.shape[0])))[0]
    assert rho == pytest.approx(stats.pearsonr(a.ravel(), b.ravel())[0], abs=1e-12)
    # One replicate by brute force: draw tiles, concatenate their pixels, correlate.
    counts = draw_counts(sums.shape[0], 1, 7)
    picked_a, picked_b = [], []
    for t, c in enumerate(counts[0].astype(int)):
        ys, xs = np.nonzero(labels == t)
        for _ in range(c):
            picked_a.append(a[ys, xs])
            picked_b.append(b[ys, xs])
    want = stats.pearsonr(np.concatenate(picked_a), np.concatenate(picked_b))[0]
    assert bootstrap_replicates(sums, counts)[0] == pytest.approx(want, abs=1e-12)
    assert (counts.sum(axis=1) == sums.shape[0]).all()


def test_iid_fields_give_about_the_fisher_interval():
    rng = np.random.default_rng(2)
    a = rng.normal(size=(192, 256))
    b = 0.5 * a + rng.normal(size=a.shape)
    out = _boot(a, b, tile=16)
    fisher = out["fisher_high"] - out["fisher_low"]
    boot = out["boot_high"] - out["boot_low"]
    assert boot / fisher == pytest.approx(1.0, abs=0.15)
    assert out["boot_low"] < out["rho"] < out["boot_high"]


def test_a_smooth_field_widens_the_interval_by_the_effective_sample_size():
    """For independent fields with autocorrelations r_a, r_b, var(rho) = sum_h r_a r_b / n."""
    rng = np.random.default_rng(3)
    width = 2.0
    shape = (256, 320)
    a = ndimage.gaussian_filter(rng.normal(size=shape), width, mode="wrap")
    b = ndimage.gaussian_filter(rng.normal(size=shape), width, mode="wrap")
    # autocorrelation of the smoothing: the kernel convolved with itself, normalised
    impulse = np.zeros((41, 41))
    impulse[20, 20] = 1.0
    kernel = ndimage.gaussian_filter(impulse, width)
    auto = ndimage.convolve(kernel, kernel[::-1, ::-1], mode="constant")
    auto /= auto.max()
    factor = math.sqrt(float((auto * auto).sum()))
    out = _boot(a, b, tile=32)
    ratio = (out["boot_high"] - out["boot_low"]) / (out["fisher_high"] - out["fisher_low"])
    assert factor > 4
    assert ratio == pytest.approx(factor, rel=0.3)


def test_a_region_with_one_tile_gets_a_nan_interval_with_a_reason():
    rng = np.random.default_rng(4)
    a, b = rng.normal(size=(2, 64, 64))
    settings = AnalysisSettings(bootstrap=BootstrapSettings(16, 200, 0))
    mask = np.zeros(a.shape, bool)
    mask[:16, :16] = True
    out = evaluate(
        METHODS.get("warp"),
        _fields(a, b),
        mask,
        settings=settings,
        labels=tile_labels(a.shape, 16),
        draws=BootstrapDraws(settings.bootstrap, 0),
    )
    assert math.isfinite(out["rho"]) and out["n_tiles"] == 1
    assert math.isnan(out["boot_low"]) and out["reason"] == FEWER_THAN_2_TILES


def test_a_tile_larger_than_the_image_is_an_error():
    with pytest.raises(ValueError, match="analysis.bootstrap.tile"):
        tile_labels((10, 20), 16)


def test_percentile_interval_is_numpys_quantile():
    r = np.random.default_rng(5).normal(size=999)
    assert percentile_interval(r) == pytest.approx(tuple(np.quantile(r, [0.025, 0.975])))


def test_robust_transforms_against_brute_force():
    rng = np.random.default_rng(6)
    a = rng.lognormal(size=5000)
    b = a * rng.lognormal(sigma=0.3, size=5000)
    a[:3] = 1e4  # fireflies
    keep = trim_mask(a, b, 0.001)
    k = math.ceil(0.001 * a.size)
    top_a = set(np.argsort(a)[-k:])
    top_b = set(np.argsort(b)[-k:])
    assert set(np.flatnonzero(~keep)) == top_a | top_b
    logs, floor = log_floor(np.array([0.0, 2.0, 3.0]))
    assert floor == 2.0 and logs == pytest.approx(np.log([2.0, 2.0, 3.0]))
    za, zb = (a - a.mean()) / a.std(), (b - b.mean()) / b.std()
    p = np.sort(za * zb)
    assert top_share(a, b) == pytest.approx(p[-k:].sum() / p.sum())
    assert top_share(a, b) > 0.5  # three fireflies decide Pearson here
    want = int(((a > 100 * np.median(a)) | (b > 100 * np.median(b))).sum())
    assert firefly_count(a, b, 100.0) == want >= 3


def test_registered_robust_statistics_match_scipy():
    rng = np.random.default_rng(7)
    a = rng.lognormal(size=(60, 80))
    b = a * rng.lognormal(sigma=0.5, size=a.shape)
    mask = rng.random(a.shape) > 0.2
    settings = AnalysisSettings()
    got = {
        m: evaluate(METHODS.get(m), _fields(a, b), mask, settings=settings)["rho"]
        for m in ("warp", "spearman", "log")
    }
    assert got["warp"] == pytest.approx(stats.pearsonr(a[mask], b[mask])[0], abs=1e-12)
    assert got["spearman"] == pytest.approx(stats.spearmanr(a[mask], b[mask])[0], abs=1e-12)
    assert got["log"] == pytest.approx(
        stats.pearsonr(np.log(a[mask]), np.log(b[mask]))[0], abs=1e-12
    )


def test_spearman_brown_and_disattenuation():
    assert spearman_brown(0.5) == pytest.approx(2 / 3)
    assert spearman_brown(1.0) == 1.0
    rho, above = attenuation_corrected(0.5, 0.25, 1.0)
    assert rho == 1.0 and not above
    rho, above = attenuation_corrected(0.6, 0.25, 1.0)
    assert rho == pytest.approx(1.2) and above


def _stereo(shape, d):
    h, w = shape
    gt = {
        "disparity": np.full(shape, float(d)),
        "valid": np.ones(shape, bool),
        "glass": np.zeros(shape, bool),
    }
    return gt


def test_attenuation_correction_recovers_the_true_rho():
    """True fields with rho 0.8, halves = truth + independent noise of known reliability."""
    from stereovar.statistics.fields import AnalysisSettings
    from stereovar.statistics.rows import SceneInputs
    from stereovar.statistics.rows import correlation_rows as rows_of
    from stereovar.statistics.warp import align_variance

    rng = np.random.default_rng(8)
    h, w, d = 200, 300, 5
    true_l = rng.normal(size=(h, w))
    true_r_aligned = 0.8 * true_l + 0.6 * rng.normal(size=(h, w))
    true_r = np.zeros((h, w))
    true_r[:, d:] = true_r_aligned[:, : w - d]  # x_R = x_L + d
    halves = {}
    for view, truth in (("left", true_l), ("right", true_r)):
        halves[view] = np.stack([truth + 1.2 * rng.normal(size=(h, w)) for _ in range(2)])
    full = {v: halves[v].mean(axis=0) for v in halves}
    gt = _stereo((h, w), d)
    aligned = align_variance(full["left"], full["right"], gt, sign=1)
    rows = rows_of(
        full["left"],
        full["right"],
        aligned,
        gt["glass"],
        settings=AnalysisSettings(bootstrap=BootstrapSettings(16, 200, 0)),
        inputs=SceneInputs(ground_truth_left=gt, sign=1, halves=halves, n_seeds=8),
    )
    row = next(r for r in rows if (r["region"], r["method"]) == ("all", "warp"))
    reliability = 1 / (1 + 1.2**2 / 2)  # var(T) = 1, noise of the mean of two halves
    assert row["reliability_left"] == pytest.approx(reliability, abs=0.02)
    assert row["rho"] < 0.8 * reliability + 0.03
    assert row["rho_corrected"] == pytest.approx(0.8, abs=0.02)


def test_fewer_than_4_seeds_give_nan_reliability_with_a_reason():
    from stereovar.statistics.rows import SceneInputs
    from stereovar.statistics.rows import correlation_rows as rows_of
    from stereovar.statistics.warp import align_variance

    rng = np.random.default_rng(9)
    left, right = rng.lognormal(size=(2, 40, 60))
    gt = _stereo(left.shape, 3)
    aligned = align_variance(left, right, gt, sign=1)
    rows = rows_of(
        left,
        right,
        aligned,
        gt["glass"],
        inputs=SceneInputs(ground_truth_left=gt, sign=1, n_seeds=3),
    )
    row = rows[0]
    assert math.isfinite(row["rho"]) and math.isnan(row["rho_corrected"])
    assert "at least 4 seeds" in row["note"]


def test_seed_subsets_match_numpy_on_every_subset():
    rng = np.random.default_rng(10)
    images = rng.normal(size=(11, 6, 7, 3))
    acc, moments = SeedSubsets(), StreamingVariance()
    for image in images:
        acc.update(image)
        moments.update(image)
    ds = subset_dataset(acc, moments.half_variance)
    np.testing.assert_allclose(
        ds["half_variance"].sel(half="even"), images[0::2].var(axis=0).mean(-1), rtol=1e-5
    )
    np.testing.assert_allclose(
        ds["half_variance"].sel(half="odd"), images[1::2].var(axis=0).mean(-1), rtol=1e-5
    )
    sizes = ds["subset_size"].values.tolist()
    assert sizes == [2] * 5 + [4] * 2 + [8]
    for k, (size, index) in enumerate(zip(sizes, ds["subset_index"].values, strict=True)):
        want = images[index * size : (index + 1) * size].var(axis=0).mean(-1)
        np.testing.assert_allclose(ds["subset_variance"][k], want, rtol=1e-5, atol=1e-7)
    n, mean, m2 = pooled_moments((1, images[0], None), (1, images[1], None))
    np.testing.assert_allclose(m2 / n, images[:2].var(axis=0))
    few = StreamingVariance()
    for image in images[:3]:
        few.update(image)
    assert few.half_variance is None
    assert "half_variance" not in subset_dataset(SeedSubsets().update(images[0]), None)


def test_reference_rows_still_give_eq3_for_the_field_statistics():
    rng = np.random.default_rng(11)
    left = rng.lognormal(size=(30, 40))
    right = np.roll(left, 2, axis=1)
    gt = _stereo(left.shape, 2)
    rows = correlation_rows(left, right, gt, sign=1)
    by = {(r["region"], r["method"]): r for r in rows}
    assert by["all", "warp"]["rho"] == pytest.approx(1.0)
    assert by["all", "spearman"]["rho"] == pytest.approx(1.0)


def test_seed_curve_matches_numpy_on_every_subset_with_a_nan_render():
    """rho(N') per subset, region and curve statistic against Eq. 1-3 done by hand."""
    from stereovar.statistics.rows import SceneInputs, seed_curve_rows, subset_rhos
    from stereovar.statistics.warp import align_variance

    rng = np.random.default_rng(12)
    n, h, w, shift = 8, 10, 24, 2
    scale = rng.lognormal(size=(h, w + shift, 1))
    left = rng.normal(size=(n, h, w, 3)) * scale[:, shift:]
    right = rng.normal(size=(n, h, w, 3)) * scale[:, :w]  # x_R = x_L + 2 sees x_L's scale
    right[3, 4, 7, 1] = np.nan  # spoils right pixel x = 7 of row 4 in one seed
    views = {}
    for name, images in (("left", left), ("right", right)):
        acc, moments = SeedSubsets(), StreamingVariance()
        for image in images:
            acc.update(image)
            moments.update(image)
        ds = subset_dataset(acc, moments.half_variance)
        views[name] = (moments, ds)
    gt = {"disparity": np.full((h, w), float(shift)), "valid": np.ones((h, w), bool)}
    glass = np.zeros((h, w), bool)
    glass[:, :8] = True
    aligned = align_variance(
        views["left"][0].variance,
        views["right"][0].variance,
        gt,
        sign=1,
        finite_right=views["right"][0].finite,
    )
    subsets = {
        k: (
            ds["subset_size"].values,
            ds["subset_index"].values,
            ds["subset_variance"].values,
        )
        for k, (_, ds) in views.items()
    }
    inputs = SceneInputs(ground_truth_left=gt, sign=1, n_seeds=n)
    got = subset_rhos(subsets, aligned, glass, inputs=inputs)

    omega = np.zeros((h, w), bool)
    omega[:, : w - shift] = True
    omega[4, 7 - shift] = False  # its warped value reads the NaN pixel with weight 1
    assert np.array_equal(aligned["omega"], omega)
    masks = {"all": omega, "non_glass": omega & ~glass, "glass": omega & glass}

    def logs(v):
        return np.log(np.maximum(v, v[v > 0].min()))

    for size in (2, 4):
        for i in range(n // size):
            sl = slice(i * size, (i + 1) * size)
            var_l = left[sl].var(axis=0).mean(-1)
            warped = np.full((h, w), np.nan)
            warped[:, : w - shift] = right[sl].var(axis=0).mean(-1)[:, shift:]
            for region, mask in masks.items():
                a, b = var_l[mask], warped[mask]
                want = {"warp": stats.pearsonr(a, b)[0], "log": stats.pearsonr(logs(a), logs(b))[0]}
                for method, value in want.items():
                    assert got[region, method, size][i] == pytest.approx(value, abs=1e-6)
    assert sorted({k[2] for k in got}) == [2, 4]
    rows = [{"region": r, "method": m, "rho": 0.5} for r in masks for m in ("warp", "log")]
    curve = seed_curve_rows(subsets, aligned, glass, rows, n_seeds=n, inputs=inputs, values=got)
    by = {(r["region"], r["method"], r["n_prime"]): r for r in curve}
    assert by["glass", "log", 2]["n_subsets"] == 4
    assert by["glass", "log", 2]["mean_rho"] == pytest.approx(np.mean(got["glass", "log", 2]))
    assert by["all", "warp", n]["mean_rho"] == 0.5


def test_warped_field_samples_match_the_full_warp_with_non_finite_pixels():
    from stereovar.statistics.fields import warp_field
    from stereovar.statistics.warp import WarpPlan

    rng = np.random.default_rng(13)
    h, w = 9, 30
    right = rng.random((h, w))
    right[2, 5] = np.nan
    right[6, 11] = np.inf
    gt = {"disparity": rng.uniform(0.5, 6.0, (h, w)), "valid": rng.random((h, w)) > 0.1}
    want = warp_field(right, gt, sign=-1)
    plan = WarpPlan(gt["disparity"], sign=-1, valid=gt["valid"])
    field = plan.field(right)
    np.testing.assert_array_equal(np.asarray(field), want)
    index = np.flatnonzero(plan.omega)[::3]
    np.testing.assert_array_equal(field.at(index), want.ravel()[index])
    assert np.isnan(want).any() and np.isfinite(want[plan.omega]).sum() > 100
    with pytest.raises(ValueError, match="valid set"):
        field.at(np.flatnonzero(~plan.omega)[:2])


def test_mid_ranks_match_scipy_with_ties_zeros_and_one_value():
    from stereovar.statistics.robust import ranks

    rng = np.random.default_rng(14)
    for values in (
        rng.integers(0, 6, size=500).astype(float),
        np.r_[np.zeros(40), rng.lognormal(size=200)],
        rng.random(300),
        np.array([2.5]),
    ):
        np.testing.assert_array_equal(ranks(values), stats.rankdata(values, method="average"))
    assert ranks(np.empty(0)).size == 0


def test_pixel_set_within_a_parent_reads_the_same_values_in_its_own_order():
    from stereovar.statistics.bootstrap import tile_labels
    from stereovar.statistics.pixels import PixelSet
    from stereovar.statistics.warp import WarpPlan

    rng = np.random.default_rng(15)
    h, w = 12, 40
    gt = {"disparity": rng.uniform(0.5, 6.0, (h, w)), "valid": rng.random((h, w)) > 0.1}
    plan = WarpPlan(gt["disparity"], sign=1, valid=gt["valid"])
    glass = rng.random((h, w)) > 0.7
    labels = tile_labels((h, w), 4)
    right, left = rng.random((h, w)), rng.random((h, w))
    warped = plan.field(right)
    for parent_labels in (None, labels):
        parent = PixelSet(plan.omega, parent_labels)
        child = PixelSet(plan.omega & glass, labels, parent=parent)
        direct = PixelSet(plan.omega & glass, labels)
        np.testing.assert_array_equal(child.index, direct.index)
        np.testing.assert_array_equal(child.values(left), left.ravel()[direct.index])
        want = np.asarray(warped).ravel()[direct.index]
        np.testing.assert_array_equal(child.values(warped), want)
        child.forget()
        assert not child._values
    with pytest.raises(ValueError, match="parent"):
        PixelSet(~plan.omega, parent=PixelSet(plan.omega))
