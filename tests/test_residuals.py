"""Cross-view residual correlation against a brute-force loop and analytic cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy import stats

from stereovar.statistics.bootstrap import BootstrapSettings
from stereovar.statistics.residuals import residual_correlation, seed_residuals

SETTINGS = BootstrapSettings(tile=4, reps=400, seed=1)


def brute_force_rho(left, right, disparity, sign, mask, alignment):
    """Pearson over explicitly listed (seed, pixel) pairs, each pixel's residuals standardised
    over its seeds, with Python loops."""
    n, h, w = left.shape[:3]
    lum_l = [
        [[float(np.mean(left[k, y, x])) for x in range(w)] for y in range(h)] for k in range(n)
    ]
    lum_r = [
        [[float(np.mean(right[k, y, x])) for x in range(w)] for y in range(h)] for k in range(n)
    ]

    def residual(lum, k, y, x):
        return lum[k][y][x] - sum(lum[m][y][x] for m in range(n)) / n

    def standardise(values):
        mean = sum(values) / n
        sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1))
        return [(v - mean) / sd for v in values]

    xs, ys = [], []
    for y in range(h):
        for x in range(w):
            if not mask[y, x]:
                continue
            if alignment == "zero":
                xs += standardise([residual(lum_l, k, y, x) for k in range(n)])
                ys += standardise([residual(lum_r, k, y, x) for k in range(n)])
                continue
            d = float(disparity[y, x])
            pos = x + sign * d
            if not (d > 0 and 0 <= pos <= w - 1):
                continue
            x0 = min(math.floor(pos), w - 2)
            t = pos - x0
            xs += standardise([residual(lum_l, k, y, x) for k in range(n)])
            ys += standardise(
                [
                    (1 - t) * residual(lum_r, k, y, x0) + t * residual(lum_r, k, y, x0 + 1)
                    for k in range(n)
                ]
            )
    xs, ys = np.array(xs), np.array(ys)
    mx, my = xs.sum() / xs.size, ys.sum() / ys.size
    num = sum((a - mx) * (b - my) for a, b in zip(xs, ys, strict=True))
    den = math.sqrt(sum((a - mx) ** 2 for a in xs) * sum((b - my) ** 2 for b in ys))
    return num / den, xs.size // n


@pytest.mark.parametrize("sign", [1, -1])
def test_against_brute_force_loop(sign):
    rng = np.random.default_rng(4)
    n, h, w = 4, 12, 16
    base = rng.standard_normal((n, h, w, 3))
    left = base + 0.3 * rng.standard_normal((n, h, w, 3))
    right = np.roll(base, 2 * sign, axis=2) + 0.5 * rng.standard_normal((n, h, w, 3))
    disparity = rng.uniform(0.5, 4.5, (h, w))
    glass = np.zeros((h, w), bool)
    glass[:, :5] = True
    masks = {"all": np.ones((h, w), bool), "glass": glass}
    rows = residual_correlation(
        left, right, disparity, sign=sign, masks=masks, settings=SETTINGS, min_pixels=4
    )
    assert [(r["region"], r["alignment"]) for r in rows] == [
        ("all", "ground_truth"),
        ("all", "zero"),
        ("glass", "ground_truth"),
        ("glass", "zero"),
    ]
    for row in rows:
        rho, n_pixels = brute_force_rho(
            left, right, disparity, sign, masks[row["region"]], row["alignment"]
        )
        assert_allclose(row["rho"], rho, rtol=1e-12, atol=1e-12)
        assert row["n_pixels"] == n_pixels and row["n_seeds"] == n
        assert row["low"] <= row["rho"] <= row["high"]
        assert row["reason"] == ""


def test_identical_views_at_zero_disparity_give_one():
    """Baseline 0 with shared seeds: both views render the same image."""
    rng = np.random.default_rng(0)
    left = rng.gamma(2.0, 0.2, (5, 16, 20, 3)).astype(np.float32)
    rows = residual_correlation(
        left,
        left.copy(),
        np.full((16, 20), 1.0),
        sign=1,
        masks={"all": np.ones((16, 20), bool)},
        alignments=("zero",),
        settings=SETTINGS,
    )
    assert_allclose(rows[0]["rho"], 1.0, rtol=0, atol=1e-12)
    assert_allclose([rows[0]["low"], rows[0]["high"]], 1.0, atol=1e-12)


def test_shifted_copy_gives_one_at_ground_truth_alignment():
    """Right = left shifted by d pixels (x_R = x_L + s d): the GT alignment pairs each left
    residual with itself; zero disparity does not."""
    rng = np.random.default_rng(2)
    n, h, w, d = 6, 16, 32, 3
    left = rng.standard_normal((n, h, w, 3))
    for sign in (1, -1):
        right = np.roll(left, sign * d, axis=2)  # right[x + s d] = left[x]
        rows = residual_correlation(
            left,
            right,
            np.full((h, w), float(d)),
            sign=sign,
            masks={"all": np.ones((h, w), bool)},
            settings=SETTINGS,
        )
        gt, zero = rows
        assert gt["n_pixels"] == h * (w - d)  # the warp's valid set
        assert_allclose(gt["rho"], 1.0, atol=1e-12)
        assert abs(zero["rho"]) < 0.1


def test_independent_seeds_give_about_zero():
    """Independent views: every rho within 4 standard errors of 0, and the 95% interval
    covers 0 about as often as it should (percentile intervals from 36 tiles cover a little
    under 95%; the floor is the 0.1% quantile of Binomial(datasets, 0.90))."""
    n, h, w, datasets = 8, 48, 48, 40
    covered = {"ground_truth": 0, "zero": 0}
    for s in range(datasets):
        rng = np.random.default_rng(100 + s)
        left = 1.0 + rng.standard_normal((n, h, w, 3))
        right = 1.0 + rng.standard_normal((n, h, w, 3))
        rows = residual_correlation(
            left,
            right,
            np.full((h, w), 2.5),
            sign=1,
            masks={"all": np.ones((h, w), bool)},
            settings=BootstrapSettings(tile=8, reps=500, seed=s),
        )
        for row in rows:
            pairs = row["n_pixels"] * n
            # independent pairs: rho ~ N(0, 1/pairs); the warp's bilinear mixing only shrinks it
            assert abs(row["rho"]) < 4 / math.sqrt(pairs)
            covered[row["alignment"]] += row["low"] < 0 < row["high"]
    floor = stats.binom.ppf(0.001, datasets, 0.90)
    assert min(covered.values()) >= floor, covered


def test_nonfinite_pixels_dropped_and_reasons():
    rng = np.random.default_rng(3)
    n, h, w = 3, 8, 10
    left = rng.standard_normal((n, h, w, 3))
    right = left.copy()
    left[1, 2, 3, 0] = np.nan
    right[0, 5, 5, 2] = np.inf
    mask = np.ones((h, w), bool)
    rows = residual_correlation(
        left,
        right,
        np.full((h, w), 1.0),
        sign=1,
        masks={"all": mask},
        settings=SETTINGS,
        min_pixels=4,
    )
    gt, zero = rows
    assert zero["n_pixels"] == h * w - 2 and zero["rho"] == pytest.approx(1.0, abs=1e-12)
    # GT (d = 1): column w-1 leaves the image; (2, 3) is non-finite on the left; (5, 4)
    # reads right (5, 5) with weight 1 ((5, 3) gives it weight 0 and stays)
    assert gt["n_pixels"] == h * (w - 1) - 2
    few = residual_correlation(
        left,
        right,
        np.full((h, w), 1.0),
        sign=1,
        masks={"all": mask},
        settings=SETTINGS,
        min_pixels=h * w + 1,
    )
    assert np.isnan(few[0]["rho"]) and f"fewer than {h * w + 1} valid pixels" in few[0]["reason"]
    flat = np.ones((n, h, w, 3))
    const = residual_correlation(
        flat,
        right,
        np.full((h, w), 1.0),
        sign=1,
        masks={"all": mask},
        settings=SETTINGS,
        min_pixels=4,
    )
    assert all(r["reason"] == "constant field in region" for r in const)


def test_seed_residuals_average_channels():
    stack = np.arange(2 * 2 * 2 * 3, dtype=np.float64).reshape(2, 2, 2, 3)
    stack[1] *= 3
    residuals, finite = seed_residuals(stack)
    lum = stack.mean(axis=-1)
    assert_allclose(residuals, lum - lum.mean(axis=0))
    assert finite.all()
    with pytest.raises(ValueError, match="at least 2 seeds"):
        seed_residuals(stack[:1])
