"""Image-quality cost of a mitigation against a converged reference of the same view.

A mitigation that removes the cue is only useful if the images stay close to what the
renderer converges to. This module compares a view's images :math:`Y_k` (transformed or not)
with a reference mean :math:`R` (the mean of many seeds, or a high-SPP moments render) whose
own estimator variance :math:`V` is known, so the reference's noise can be taken out of the
error. Radiance is in the renderer's linear units: a white diffuse surface under the scene's
key light is about 1 (as the sensor model assumes, :mod:`stereovar.controls.sensor`), so PSNR
uses peak 1.

The reference must be independent of the images (other seeds, or a separate render): if
:math:`Y` is one of the :math:`N` seeds averaged into :math:`R`, then
:math:`\\mathrm E[(Y - R)^2] = \\sigma^2 (1 - 1/N)` and the correction below subtracts
:math:`\\sigma^2/N` too many.
"""

from __future__ import annotations

import math

import numpy as np

RELATIVE_EPSILON = 0.01
"""The relative MSE's denominator offset, :math:`(R^2 + 0.01)` (Rousselle, Knaus and Zwicker
2011)."""

PEAK = 1.0
"""PSNR peak: the radiance of a white diffuse surface under the key light."""

RESULT_KEYS = (
    "mse",
    "mse_raw",
    "reference_noise",
    "psnr",
    "relative_mse",
    "bias",
    "relative_bias",
    "reference_mean",
    "n_pixels",
    "n_images",
    "reason",
)

NOT_ABOVE_NOISE = "error not above the reference's own noise (corrected MSE <= 0)"


def image_quality(
    images,
    reference,
    *,
    reference_var=None,
    mask=None,
    peak: float = PEAK,
    epsilon: float = RELATIVE_EPSILON,
) -> dict:
    """MSE, PSNR, relative MSE and mean bias of images against a noisy converged reference.

    Over the :math:`n` images :math:`Y_k`, the :math:`P` pixels of the mask where every image,
    :math:`R` and :math:`V` is finite in every channel, and the :math:`C` channels
    (:math:`M = nPC` terms, accumulated in float64):

    .. math::

        \\mathrm{MSE} = \\frac1M \\sum_{k,p,c} (Y - R)^2 - \\frac1{PC} \\sum_{p,c} V,
        \\qquad \\mathrm{PSNR} = 10 \\log_{10} \\frac{\\text{peak}^2}{\\mathrm{MSE}},

        \\mathrm{relMSE} = \\frac1M \\sum_{k,p,c} \\frac{(Y - R)^2}{R^2 + 0.01}
            - \\frac1{PC} \\sum_{p,c} \\frac{V}{R^2 + 0.01},

        \\mathrm{bias} = \\frac1M \\sum_{k,p,c} (Y - R), \\qquad
        \\text{relative bias} = \\frac{\\mathrm{bias}}{\\frac1{PC}\\sum_{p,c} R}.

    With :math:`R = R^\\ast + e`, :math:`\\mathrm E[e] = 0`, :math:`\\operatorname{Var}[e] = V`
    and :math:`e` independent of :math:`Y`,
    :math:`\\mathrm E[(Y - R)^2] = \\mathrm E[(Y - R^\\ast)^2] + V`, so the corrected MSE is
    unbiased for the error against the converged image :math:`R^\\ast`. The relative MSE's
    correction is the same with the denominator taken as fixed (first order in :math:`e`;
    exact when :math:`V = 0`). The mean bias needs no correction.

    Parameters
    ----------
    images : array_like, shape (n, H, W, C) or (H, W, C)
        The view's images.
    reference : array_like, shape (H, W, C)
        The reference mean :math:`R`.
    reference_var : array_like, shape (H, W, C), keyword-only, optional
        Variance of the reference mean :math:`V` (e.g. a moments render's variance divided
        by its sample count, or the seed variance divided by :math:`N`); None treats the
        reference as exact.
    mask : array_like of bool, shape (H, W), keyword-only, optional
        Region (all pixels when None).
    peak : float, keyword-only
        PSNR peak (:data:`PEAK`).
    epsilon : float, keyword-only
        The relative MSE's offset (:data:`RELATIVE_EPSILON`).

    Returns
    -------
    dict
        :data:`RESULT_KEYS`: ``mse`` (corrected), ``mse_raw`` (uncorrected), ``reference_noise``
        (the mean of :math:`V`), ``psnr``, ``relative_mse``, ``bias``, ``relative_bias``,
        ``reference_mean`` (the mean of :math:`R`),
        ``n_pixels``, ``n_images``, and ``reason``: ``""``, or why ``psnr`` (or everything) is
        NaN: no usable pixel, or a corrected MSE not above 0.
    """
    y = np.asarray(images)
    if y.ndim == 3:
        y = y[None]
    r = np.asarray(reference, dtype=np.float64)
    if y.ndim != 4 or y.shape[1:] != r.shape or r.ndim != 3:
        raise ValueError(
            f"images must be (n, H, W, C) with the reference's (H, W, C); got {y.shape} and "
            f"{r.shape}"
        )
    v = np.zeros_like(r) if reference_var is None else np.asarray(reference_var, np.float64)
    if v.shape != r.shape:
        raise ValueError(f"reference_var shape {v.shape} differs from the reference's {r.shape}")
    keep = np.ones(r.shape[:2], bool) if mask is None else np.asarray(mask, dtype=bool)
    if keep.shape != r.shape[:2]:
        raise ValueError(f"mask shape {keep.shape} differs from the images' {r.shape[:2]}")
    keep = keep & np.isfinite(r).all(-1) & np.isfinite(v).all(-1) & np.isfinite(y).all((0, -1))
    n_images, n_pixels = y.shape[0], int(keep.sum())
    nan = float("nan")
    result = dict.fromkeys(RESULT_KEYS, nan)
    result.update(n_pixels=n_pixels, n_images=n_images, reason="")
    if n_pixels == 0:
        result["reason"] = "no pixel of the region is finite in every image and the reference"
        return result
    rv, vv = r[keep], v[keep]  # (P, C)
    weight = 1.0 / (rv * rv + epsilon)
    diff = y[:, keep].astype(np.float64) - rv  # (n, P, C)
    sq = diff * diff
    mse_raw = float(sq.mean())
    noise = float(vv.mean())
    mse = mse_raw - noise
    result.update(
        mse=mse,
        mse_raw=mse_raw,
        reference_noise=noise,
        relative_mse=float((sq * weight).mean() - (vv * weight).mean()),
        bias=float(diff.mean()),
    )
    mean_r = float(rv.mean())
    result["reference_mean"] = mean_r
    result["relative_bias"] = result["bias"] / mean_r if mean_r != 0 else nan
    if mse > 0:
        result["psnr"] = 10.0 * math.log10(float(peak) ** 2 / mse)
    else:
        result["reason"] = NOT_ABOVE_NOISE
    return result
