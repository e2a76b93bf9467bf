"""The single-render noise estimators (stereovar.estimators.single) on synthetic images whose
per-pixel variance is known."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.stats import spearmanr

from stereovar.estimators.single import (
    MAD_TO_SD,
    box_sums,
    diagonal_detail,
    local_mad_variance,
    poisson_gaussian_variance,
    residual_variance,
    single_render_field,
    window_variance,
)

H, W = 96, 128


def smooth_variance(scale: float = 0.01) -> np.ndarray:
    """A smooth variance field spanning a factor of 9 (known truth)."""
    y, x = np.indices((H, W), dtype=np.float64)
    return scale * (1.0 + 0.8 * np.sin(2 * np.pi * x / W) * np.cos(2 * np.pi * y / H))


def linear_image() -> np.ndarray:
    """A smooth (linear) clean image, three channels."""
    y, x = np.indices((H, W), dtype=np.float64)
    base = 0.5 + 0.2 * x / W - 0.1 * y / H
    return np.stack([base, 0.8 * base, 1.2 * base], axis=-1)


def noisy(clean, variance, seed=0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return clean + np.sqrt(variance)[..., None] * rng.standard_normal(clean.shape)


def test_box_sums_match_a_brute_force_window_sum_at_the_border_and_inside():
    rng = np.random.default_rng(1)
    field = rng.standard_normal((9, 11))
    sums, counts = box_sums(field, window=5)
    for (y, x) in [(0, 0), (4, 5), (8, 10), (2, 9)]:
        block = field[max(y - 2, 0) : y + 3, max(x - 2, 0) : x + 3]
        assert_allclose(sums[y, x], block.sum(), atol=1e-12)
        assert counts[y, x] == block.size


def test_window_variance_is_the_unbiased_sample_variance_of_each_window():
    """Brute force: numpy's ddof=1 variance of the window's pixels, channels averaged."""
    rng = np.random.default_rng(2)
    r = rng.standard_normal((10, 12, 3)) + 4.0
    v = window_variance(r, window=3)
    for (y, x) in [(0, 0), (5, 6), (9, 11), (0, 7)]:
        block = r[max(y - 1, 0) : y + 2, max(x - 1, 0) : x + 2].reshape(-1, 3)
        assert_allclose(v[y, x], block.var(axis=0, ddof=1).mean(), rtol=1e-9)


def test_window_mean_correction_makes_an_offset_residual_unbiased():
    """Noise of variance s^2 on a constant offset m: the estimate's mean is s^2, not
    s^2 + m^2. Over ~(96*128)/49 independent 7x7 windows and 3 channels the relative
    standard error of the mean of unbiased sample variances (each with relative sd
    sqrt(2/48)) is about 0.2 / sqrt(250 * 3) < 0.01; 4% is four of them."""
    s2 = 0.09
    r = noisy(np.full((H, W, 3), 5.0), np.full((H, W), s2), seed=3)
    v = window_variance(r, window=7)
    assert abs(v.mean() / s2 - 1.0) < 0.04
    # a constant image has none
    assert window_variance(np.full((H, W, 3), 5.0), window=7).max() == 0.0


def test_residual_variance_with_an_ideal_denoiser_tracks_the_known_field():
    """With D(I) the clean image, the residual is the noise: the estimate follows the known
    smooth variance field (rank correlation) and matches it on average."""
    truth = smooth_variance()
    clean = linear_image()
    image = noisy(clean, truth, seed=4)
    est = residual_variance(image, clean, window=7)
    assert spearmanr(est.ravel(), truth.ravel()).statistic > 0.85
    assert abs(est.mean() / truth.mean() - 1.0) < 0.04


def test_diagonal_detail_has_the_noise_variance_on_a_linear_image():
    """Var d = the mean of the four pixels' variances: sigma^2 for a constant field."""
    image = noisy(linear_image(), np.full((H, W), 0.04), seed=5)
    d = diagonal_detail(image)[:-1, :-1]
    assert abs(d.var() / 0.04 - 1.0) < 0.03  # ~36 000 values: se of the variance ~0.75%
    assert abs(np.median(np.abs(d)) / (MAD_TO_SD * 0.2) - 1.0) < 0.03


def test_local_mad_variance_follows_a_known_smooth_variance_field():
    """The local MAD estimate on a smooth image plus noise of known smooth variance.

    Its scale: the median of n = 49 half-normal values has relative standard deviation
    1 / (2 sqrt(n) f(m) m) = 0.17 (f the half-normal density at its median m), so squaring
    it biases sigma^2 up by 0.17^2 = 3% for independent values, and by more for the
    undecimated subband, whose neighbours share pixels (correlation -1/2): at most 12% here.
    Measured on a constant field, that factor must then carry over to the smooth field
    within the random part (< 1% over ~250 windows and 3 channels) plus the field's change
    across a window (< 3%)."""
    rng_image = linear_image()
    flat = local_mad_variance(noisy(rng_image, np.full((H, W), 0.01), seed=9), window=7)
    kappa = flat.mean() / 0.01
    assert 1.0 < kappa < 1.12
    truth = smooth_variance()
    est = local_mad_variance(noisy(rng_image, truth, seed=6), window=7)
    assert spearmanr(est.ravel(), truth.ravel()).statistic > 0.85
    assert abs(est.mean() / truth.mean() / kappa - 1.0) < 0.04


def test_the_poisson_gaussian_field_is_a_function_of_intensity_alone():
    """Foi et al.'s law a*mu + b: perfectly rank-correlated with mu (so the intensity control
    explains all of it), and on noise of variance 0.02 mu + 0.001 its slope is recovered."""
    clean = linear_image() + 0.3
    mu = clean.mean(axis=-1)
    truth = 0.02 * mu + 0.001
    image = noisy(clean, truth, seed=7)
    est = poisson_gaussian_variance(image, mu, window=7)
    assert spearmanr(est.ravel(), mu.ravel()).statistic == pytest.approx(1.0)
    assert abs(est.mean() / truth.mean() - 1.0) < 0.1


def test_single_render_field_shapes_and_the_clean_estimate_of_each_candidate():
    image = noisy(linear_image(), smooth_variance(), seed=8)
    for method in ("wavelet_mad", "poisson_gaussian"):
        field = single_render_field(image, method)
        assert field.variance.shape == (H, W) and field.mean.shape == (H, W, 3)
        assert np.isfinite(field.variance).all() and (field.variance >= 0).all()
    with pytest.raises(ValueError, match="unknown single-render method"):
        single_render_field(image, "nlm")
    with pytest.raises(ValueError, match="albedo"):
        single_render_field(image, "oidn_aux")
