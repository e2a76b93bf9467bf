"""The residual coupling standardised per pixel: one planted coupling reads the same wherever
the high-variance pixels sit; independent seeds read 0; a shared stream reads 1; the disparity
bands against a brute-force loop."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats
from scipy.special import gammaln, hyp2f1

from stereovar.statistics.bootstrap import BootstrapSettings
from stereovar.statistics.residuals import (
    ALL_BANDS,
    DISPARITY_BANDS,
    band_label,
    residual_correlation,
)

from .test_residuals import brute_force_rho

N, H, W = 8, 64, 64
SETTINGS = BootstrapSettings(tile=8, reps=300, seed=1)


def mean_sample_correlation(rho: float, n: int) -> float:
    """E[r] of n bivariate-normal pairs with correlation rho (Fisher 1915)."""
    g = math.exp(2 * gammaln(n / 2) - gammaln((n - 1) / 2) - gammaln((n + 1) / 2))
    return rho * g * float(hyp2f1(0.5, 0.5, (n + 1) / 2, rho * rho))


def pooled_raw_rho(left, right) -> float:
    """The pooled Pearson of the raw residuals (what the statistic was before it was
    standardised): weighted by sigma_L * sigma_R."""
    a = (left - left.mean(0)).ravel()
    b = (right - right.mean(0)).ravel()
    return float(np.corrcoef(a, b)[0, 1])


def scales(rng, where_right: str):
    """Per-pixel noise scale of each view: 10% of the pixels at 10, the rest at 1; the right
    view's loud pixels at the left's (``same``) or elsewhere (``elsewhere``)."""
    loud = rng.permutation(H * W)
    left = np.ones(H * W)
    left[loud[: H * W // 10]] = 10.0
    right = np.ones(H * W)
    chosen = loud[: H * W // 10] if where_right == "same" else loud[-(H * W // 10) :]
    right[chosen] = 10.0
    return left.reshape(H, W), right.reshape(H, W)


@pytest.mark.parametrize(("alignment", "shift"), [("zero", 0), ("ground_truth", 3)])
def test_a_planted_coupling_reads_the_same_wherever_the_loud_pixels_sit(alignment, shift):
    """eps_R = c eps_L + sqrt(1 - c^2) eps_indep in standardised units, at the same pixel
    (zero) or at x + 3 (ground truth, integer disparity so the warp copies a pixel). The
    loud pixels of the two views at the same place or apart: the raw pooled rho reads about
    0.5 and 0.13; the standardised rho reads the same, Fisher's E[r] for c = 0.5 and N = 8
    (0.4725), within 4 standard errors (per-pixel r has sd about (1 - c^2)/sqrt(N - 1) = 0.21,
    over about 4000 pixels: 0.0034)."""
    c = 0.5
    rng = np.random.default_rng(11)
    u_left = rng.standard_normal((N, H, W))
    u_right = c * u_left + math.sqrt(1 - c * c) * rng.standard_normal((N, H, W))
    disparity = np.full((H, W), float(shift))
    got, raw = {}, {}
    for where in ("same", "elsewhere"):
        s_left, s_right = scales(np.random.default_rng(5), where)
        left = 1.0 + s_left * u_left
        # the right view holds at x + shift what the left holds at x
        right = np.roll(1.0 + s_right * u_right, shift, axis=2)
        (row,) = residual_correlation(
            left,
            right,
            disparity,
            sign=1,
            masks={"all": np.ones((H, W), bool)},
            alignments=(alignment,),
            settings=SETTINGS,
        )
        got[where] = row
        keep = slice(0, W - shift)
        raw[where] = pooled_raw_rho(left[..., keep], right[..., shift:][..., : W - shift])
    assert raw["same"] - raw["elsewhere"] > 0.3, raw  # the defect: placement moves it
    # each pixel's r ignores its scale, so the two placements agree to rounding
    assert got["same"]["rho"] == pytest.approx(got["elsewhere"]["rho"], abs=1e-9)
    expected = mean_sample_correlation(c, N)
    se = (1 - c * c) / math.sqrt(N - 1) / math.sqrt(got["same"]["n_pixels"])
    for where, row in got.items():
        assert row["rho"] == pytest.approx(expected, abs=4 * se), where
        assert row["low"] < expected < row["high"], where


def test_a_shared_stream_with_a_per_pixel_gain_reads_one():
    """The same seed in both views, the right view's radiance a per-pixel multiple of the
    left's: every pixel's residuals are proportional, r = 1 (the raw pooled rho is not)."""
    rng = np.random.default_rng(3)
    u = rng.standard_normal((N, H, W))
    gain = rng.uniform(0.1, 10.0, (H, W))
    left, right = 1.0 + u, gain * (1.0 + u)
    (row,) = residual_correlation(
        left,
        right,
        np.zeros((H, W)),
        sign=1,
        masks={"all": np.ones((H, W), bool)},
        alignments=("zero",),
        settings=SETTINGS,
    )
    assert row["rho"] == pytest.approx(1.0, abs=1e-12)
    assert pooled_raw_rho(left, right) < 0.9


def test_independent_skewed_seeds_read_zero_with_intervals_that_cover_it():
    """Independent views whose noise is right-skewed where the other view's is too (a mean of
    4 lognormal samples, the log-spread a function of the pixel shared by both views, as a
    scene point's light paths are): the mean over 20 datasets within 4 standard errors of 0
    (per-pixel r has sd 1/sqrt(N - 1), over 48 x 48 pixels and 20 datasets), and each
    dataset's 95% interval covers 0 at least as often as the 0.1% quantile of
    Binomial(20, 0.90) (percentile intervals from 36 tiles cover a little under 95%)."""
    n, h, w, datasets = 8, 48, 48, 20
    spread = np.random.default_rng(0).uniform(0.3, 2.0, (h, w))
    rhos, covered = [], 0
    for s in range(datasets):
        rng = np.random.default_rng(200 + s)
        left, right = (np.exp(spread * rng.standard_normal((4, n, h, w))).mean(0) for _ in range(2))
        (row,) = residual_correlation(
            left,
            right,
            np.zeros((h, w)),
            sign=1,
            masks={"all": np.ones((h, w), bool)},
            alignments=("zero",),
            settings=BootstrapSettings(tile=8, reps=300, seed=s),
        )
        rhos.append(row["rho"])
        covered += row["low"] < 0 < row["high"]
    se = 1 / math.sqrt((n - 1) * h * w * datasets)
    assert abs(np.mean(rhos)) < 4 * se, np.mean(rhos)
    assert covered >= stats.binom.ppf(0.001, datasets, 0.90), covered


@pytest.mark.parametrize("sign", [1, -1])
def test_the_disparity_bands_against_a_brute_force_loop(sign):
    """Each band's row is the brute-force standardised Pearson over the pixels of the region
    whose disparity lies in the band; the bands partition the ``all`` row's pixels."""
    rng = np.random.default_rng(8)
    n, h, w = 4, 12, 40
    base = rng.standard_normal((n, h, w, 3))
    left = base + 0.4 * rng.standard_normal((n, h, w, 3))
    right = np.roll(base, 4 * sign, axis=2) + 0.6 * rng.standard_normal((n, h, w, 3))
    disparity = rng.uniform(0.2, 14.0, (h, w))
    glass = np.zeros((h, w), bool)
    glass[:, :15] = True
    masks = {"all": np.ones((h, w), bool), "glass": glass}
    rows = residual_correlation(
        left,
        right,
        disparity,
        sign=sign,
        masks=masks,
        bands=DISPARITY_BANDS,
        settings=BootstrapSettings(tile=4, reps=200, seed=0),
        min_pixels=4,
    )
    pairs = list(zip(DISPARITY_BANDS[:-1], DISPARITY_BANDS[1:], strict=True))
    labels = [ALL_BANDS] + [band_label(lo, hi) for lo, hi in pairs]
    assert labels == [ALL_BANDS, "d0-2", "d2-8", "d8-inf"]
    assert [(r["region"], r["alignment"], r["band"]) for r in rows] == [
        (region, alignment, band)
        for region in masks
        for alignment in ("ground_truth", "zero")
        for band in labels
    ]
    edges = dict(zip(labels[1:], pairs, strict=True))
    for row in rows:
        mask = masks[row["region"]]
        if row["band"] != ALL_BANDS:
            lo, hi = edges[row["band"]]
            mask = mask & (disparity >= lo) & (disparity < hi)
        rho, n_pixels = brute_force_rho(left, right, disparity, sign, mask, row["alignment"])
        assert row["rho"] == pytest.approx(rho, abs=1e-12), row
        assert row["n_pixels"] == n_pixels and row["reason"] == ""
    for region in masks:
        for alignment in ("ground_truth", "zero"):
            chosen = [r for r in rows if (r["region"], r["alignment"]) == (region, alignment)]
            assert chosen[0]["n_pixels"] == sum(r["n_pixels"] for r in chosen[1:])
