"""Agreement of two estimates of one field, against brute-force references."""

import numpy as np
from scipy import stats

from stereovar.statistics.agreement import field_agreement, mean_ratio, split_half_reliability
from stereovar.statistics.bootstrap import BootstrapSettings, draw_counts, tile_labels


def test_mean_ratio_interval_is_the_percentile_interval_of_resampled_tiles():
    rng = np.random.default_rng(0)
    a, b = rng.gamma(2.0, 1.0, 600), rng.gamma(2.0, 1.2, 600)
    labels = np.repeat(np.arange(30), 20)
    settings = BootstrapSettings(tile=4, reps=200, seed=0)
    ratio, low, high = mean_ratio(a, b, labels, settings=settings, seed=7)
    assert np.isclose(ratio, a.mean() / b.mean())
    counts = draw_counts(30, 200, 7)
    reps = []
    for row in counts:  # brute force: each replicate's tiles, pixel by pixel
        idx = np.concatenate(
            [np.flatnonzero(labels == t).repeat(int(c)) for t, c in enumerate(row)]
        )
        reps.append(a[idx].sum() / b[idx].sum())
    np.testing.assert_allclose([low, high], np.quantile(reps, [0.025, 0.975]), rtol=1e-12)


def test_field_agreement_uses_pixels_finite_in_both_and_in_the_mask():
    rng = np.random.default_rng(1)
    x = rng.lognormal(size=(24, 32))
    y = x * rng.lognormal(0.0, 0.3, size=x.shape)
    y[0, :5] = np.nan
    mask = np.ones(x.shape, bool)
    mask[-1] = False
    out = field_agreement(x, y, mask, settings=BootstrapSettings(tile=8, reps=100))
    keep = mask & np.isfinite(y)
    assert out["n_pixels"] == keep.sum()
    assert np.isclose(out["mean_ratio"], x[keep].sum() / y[keep].sum())
    assert np.isclose(out["spearman"], stats.spearmanr(x[keep], y[keep]).statistic)
    assert np.isclose(out["pearson"], np.corrcoef(x[keep], y[keep])[0, 1])
    assert out["ratio_low"] <= out["mean_ratio"] <= out["ratio_high"]
    assert tile_labels(x.shape, 8).max() == 11


def test_split_half_reliability_is_spearman_brown_of_the_half_correlation():
    rng = np.random.default_rng(2)
    truth = rng.lognormal(size=(20, 20))
    halves = truth * rng.lognormal(0.0, 0.5, size=(2, 20, 20))
    mask = np.ones((20, 20), bool)
    out = split_half_reliability(halves, mask)
    r_s = stats.spearmanr(halves[0].ravel(), halves[1].ravel()).statistic
    r_p = np.corrcoef(halves[0].ravel(), halves[1].ravel())[0, 1]
    assert np.isclose(out["reliability_spearman"], 2 * r_s / (1 + r_s))
    assert np.isclose(out["reliability_pearson"], 2 * r_p / (1 + r_p))
    assert np.isnan(
        split_half_reliability(np.ones((2, 3, 3)), np.ones((3, 3), bool))["reliability_pearson"]
    )
