"""Image-quality cost against a noisy converged reference: analytic and synthetic cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from stereovar.statistics.utility import NOT_ABOVE_NOISE, image_quality


def clean_image(shape=(40, 50, 3)):
    yy, xx = np.mgrid[0 : shape[0], 0 : shape[1]]
    return np.stack([0.2 + 0.6 * xx / shape[1], 0.5 + 0.2 * np.sin(yy / 4), 0.1 + 0 * xx], -1)


def test_corrected_mse_recovers_known_noise_variance():
    """Y = R* + N(0, s2), R = R* + N(0, V): E[(Y - R)^2] - V = s2, and the mean of M terms
    (Y - R)^2 has standard error sqrt(2 / M) (s2 + V) for Gaussian noise."""
    rng = np.random.default_rng(0)
    truth = clean_image()
    s2 = 4e-3
    v = np.full(truth.shape, 1e-3)
    v[:, :25] = 3e-3  # a reference noisier in half the image
    reference = truth + np.sqrt(v) * rng.standard_normal(truth.shape)
    images = truth + math.sqrt(s2) * rng.standard_normal((6, *truth.shape))
    out = image_quality(images.astype(np.float32), reference, reference_var=v)
    m = images.size
    # Var[(Y - R)^2] = 2 (s2 + V)^2 per term, V varying over pixels
    se = math.sqrt(np.mean(2 * (s2 + v) ** 2) / m)
    # the reference's draw is shared by the n images: add its own contribution
    se = math.hypot(se, math.sqrt(np.mean(2 * v**2) / v.size))
    assert abs(out["mse"] - s2) < 4 * se
    assert abs(out["mse_raw"] - (s2 + v.mean())) < 4 * se
    assert out["reference_noise"] == pytest.approx(v.mean())
    assert out["psnr"] == pytest.approx(10 * math.log10(1 / out["mse"]))
    assert out["n_pixels"] == truth.shape[0] * truth.shape[1] and out["n_images"] == 6


def test_constant_bias_recovered_exactly():
    truth = clean_image()
    c = 0.03
    out = image_quality(truth + c, truth)
    assert_allclose(out["bias"], c, rtol=1e-12)
    assert_allclose(out["relative_bias"], c / truth.mean(), rtol=1e-12)
    assert_allclose(out["mse"], c**2, rtol=1e-10)
    assert_allclose(out["psnr"], 10 * math.log10(1 / c**2), rtol=1e-10)
    assert_allclose(out["relative_mse"], np.mean(c**2 / (truth**2 + 0.01)), rtol=1e-10)
    assert out["reason"] == ""


def test_psnr_of_known_mse_with_peak():
    truth = np.zeros((4, 4, 3))
    images = np.stack([truth + 0.1, truth - 0.1])  # MSE 0.01, bias 0
    out = image_quality(images, truth, peak=2.0)
    assert_allclose(out["psnr"], 10 * math.log10(4.0 / 0.01), rtol=1e-12)
    assert abs(out["bias"]) < 1e-15


def test_error_below_reference_noise_gives_nan_psnr_with_reason():
    truth = clean_image((8, 8, 3))
    out = image_quality(truth, truth, reference_var=np.full(truth.shape, 1e-4))
    assert out["mse"] == pytest.approx(-1e-4) and math.isnan(out["psnr"])
    assert out["reason"] == NOT_ABOVE_NOISE


def test_mask_and_nonfinite_pixels():
    truth = clean_image((6, 7, 3))
    images = np.stack([truth + 0.1, truth + 0.1])
    images[1, 2, 3, 0] = np.nan
    mask = np.zeros((6, 7), bool)
    mask[:3] = True
    out = image_quality(images, truth, mask=mask)
    assert out["n_pixels"] == 3 * 7 - 1
    assert_allclose(out["bias"], 0.1)
    empty = image_quality(images, truth, mask=np.zeros((6, 7), bool))
    assert math.isnan(empty["mse"]) and "no pixel" in empty["reason"]
