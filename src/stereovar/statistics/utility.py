"""Image-quality cost of a mitigation against a converged reference of the same view.

A mitigation that removes the cue is only useful if the images stay close to what the
renderer converges to. This module compares a view's images :math:`Y_k` (transformed or not)
with a reference mean :math:`R` (the mean of many seeds, or a high-SPP moments render) whose
own estimator variance :math:`V` is known, so the reference's noise can be taken out of the
error. Radiance is in the renderer's linear units: a white diffuse surface under the scene's
key light is about 1 (as the sensor model assumes, :mod:`stereovar.controls.sensor`), so PSNR
uses peak 1.

The reference must be independent of the images (a separate render, :func:`image_quality`):
if :math:`Y` is one of the :math:`N` seeds averaged into :math:`R`, then
:math:`\\mathrm E[(Y - R)^2] = \\sigma^2 (1 - 1/N)` and the correction below subtracts
:math:`\\sigma^2/N` too many; and an image built from the seed mean of all :math:`N` renders
shares the noise of any mean of them. Without a separate render, :func:`split_half_quality`
grades the images against half of the renders, the images' mean part remade from the other
half.
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
    result["reference_mean"] = float(rv.mean())
    return _finish(result, mse, peak)


def split_half_quality(
    images,
    half_images,
    raw_halves,
    *,
    mask=None,
    peak: float = PEAK,
    epsilon: float = RELATIVE_EPSILON,
) -> dict:
    """MSE, PSNR, relative MSE and mean bias of a view's images when the only reference is
    the :math:`N` renders they were made from: split-half, with no converged render.

    The renders :math:`I_n` of the :math:`N` seeds are split into halves :math:`A` and
    :math:`B` of :math:`M_A` and :math:`M_B` seeds, with means :math:`R_A` and :math:`R_B`
    and :math:`\\hat\\sigma^2` the unbiased variance of all :math:`N` (per pixel and channel;
    :math:`\\mathrm E[I_n] = \\mu`, :math:`\\operatorname{Var}[I_n] = \\sigma^2`). The images
    :math:`Y_k` graded are what ships, seed by seed, with mean :math:`\\bar Y`;
    :math:`\\bar Y^A` is the mean of the images made from half :math:`A` alone (the same
    transform, its seed-mean inputs from :math:`A` only) and :math:`\\bar Y^B` likewise. Per
    pixel and channel,

    .. math::

        \\widehat{\\mathrm{MSE}} = \\underbrace{\\frac1N \\sum_k (Y_k - \\bar Y)^2}_{W}
            + \\tfrac12 (D_A + D_B) - \\kappa\\, Q, \\qquad
        D_A = (\\bar Y^A - R_B)^2 - \\frac{\\hat\\sigma^2}{M_B}, \\quad
        D_B = (\\bar Y^B - R_A)^2 - \\frac{\\hat\\sigma^2}{M_A},

        Q = (\\bar Y^A - \\bar Y^B)^2, \\qquad
        \\kappa = \\frac12 - \\frac{1/N}{1/M_A + 1/M_B}
            \\quad \\Bigl(\\tfrac14 \\text{ for equal halves}\\Bigr),

    averaged over the pixels of the mask and the channels. Why it is unbiased for the
    shipped images' error :math:`\\frac1N \\sum_k \\mathrm E(Y_k - \\mu)^2`:

    - :math:`\\frac1N \\sum_k (Y_k - \\mu)^2 = (\\bar Y - \\mu)^2 + W` exactly, and :math:`W`
      needs no reference.
    - The images' mean over :math:`M` seeds is taken to have a bias that does not depend on
      :math:`M` and a variance :math:`K/M`:
      :math:`\\mathrm E(\\bar Y^{(M)} - \\mu)^2 = b^2 + K/M`. This is exact for the renders
      themselves, for any transform of each render alone (an average of :math:`M`
      independent images), for ``equalise`` (:math:`\\bar Y = \\bar I` exactly) and for
      ``sensor_only`` (:math:`\\bar Y = \\bar I + \\bar\\eta`, camera noise of mean 0 and
      variance :math:`(a\\mu + b)/M` on non-negative renders).
    - :math:`\\bar Y^A` shares no render with :math:`R_B`, so
      :math:`\\mathrm E[D_A] = b^2 + K/M_A`; :math:`\\bar Y^A` and :math:`\\bar Y^B` are
      independent, so :math:`\\mathrm E[Q] = K/M_A + K/M_B`; and
      :math:`\\mathrm E[\\frac12(D_A + D_B) - \\kappa Q] = b^2 + K/N`.

    What is not unbiased:

    - Images that read the seed mean over all :math:`N` seeds (``equalise``,
      ``sensor_only``) graded directly against any mean of those renders, split or not: they
      share its noise. Graded against the mean of the other seeds (the former leave-one-out
      reference) or of the other half, ``sensor_only``'s error reads
      :math:`\\sigma_c^2 - \\sigma^2/N` for a truth of :math:`\\sigma_c^2 + \\sigma^2/N`
      (:math:`\\sigma_c^2 = a\\mu + b` the camera's variance; a
      bias of :math:`-2\\sigma^2/N`, below 0 where the seed mean's noise outweighs the
      camera's), ``equalise``'s :math:`2(1 - s)\\sigma^2/N` low, :math:`s` its rescaling
      factor :math:`\\sqrt{(a\\mu + b)/\\sigma^2}` (to first order). So
      :math:`\\bar Y^A`, :math:`\\bar Y^B` must be remade from each half; the shipped images
      enter through :math:`W` only.
    - A transform whose mean's bias changes with :math:`M`, or whose spread is not
      :math:`K/M` (a nonlinear function of the seed mean beyond the two above): the mean
      part is then graded at the halves' :math:`M` seeds, not :math:`N`.
    - The relative MSE takes the weight :math:`1/(\\bar I^2 + 0.01)` from all :math:`N`
      renders as fixed (first order, as :func:`image_quality`'s).

    The mean bias is :math:`\\overline{\\bar Y - \\bar I}` over all :math:`N` (linear, so
    sharing noise costs it nothing); ``reference_noise`` is the mean of the subtracted
    :math:`\\frac{\\hat\\sigma^2}2 (1/M_A + 1/M_B)` and ``mse_raw`` the estimate without it.
    The estimate is noisier than against a converged render: its spread is that of squared
    differences of half means, 0.75% of the MSE over 256 x 256 x 3 values at :math:`N = 8`
    with :math:`\\sigma^2/N` 3.5 times the camera's variance (``tests/test_split_half_quality.py``).

    Parameters
    ----------
    images : array_like, shape (N, H, W, C)
        The view's images as shipped, one per seed.
    half_images : pair of array_like, shapes (M_A, H, W, C) and (M_B, H, W, C)
        The images made from each half of the renders alone (the shipped ones of those seeds
        when an image reads its own render only).
    raw_halves : pair of array_like, shapes (M_A, H, W, C) and (M_B, H, W, C)
        The renders of each half.
    mask : array_like of bool, shape (H, W), keyword-only, optional
        Region (all pixels when None).
    peak, epsilon : float, keyword-only
        As :func:`image_quality`.

    Returns
    -------
    dict
        :data:`RESULT_KEYS`, ``reference_mean`` the mean of :math:`\\bar I`.

    Examples
    --------
    Renders graded as they are (:math:`N = 4`, one pixel, one channel): :math:`W = 1.25`,
    :math:`D_A = 4 - 5/6`, :math:`D_B = 4 - 5/6`, :math:`Q = 4`, :math:`\\kappa = 1/4`.

    >>> raw = np.array([0.0, 1.0, 2.0, 3.0]).reshape(4, 1, 1, 1)
    >>> q = split_half_quality(raw, (raw[:2], raw[2:]), (raw[:2], raw[2:]))
    >>> round(q["mse"], 6), q["bias"]
    (3.416667, 0.0)
    """
    y = _as_stack(images, "images")
    ya, yb = (_as_stack(h, "half_images") for h in half_images)
    ra, rb = (_as_stack(h, "raw_halves") for h in raw_halves)
    n, (m_a, m_b) = y.shape[0], (ra.shape[0], rb.shape[0])
    shapes = {a.shape[1:] for a in (y, ya, yb, ra, rb)}
    if len(shapes) != 1 or ya.shape[0] != m_a or yb.shape[0] != m_b or min(m_a, m_b) < 1:
        raise ValueError(
            f"images {y.shape}, half images {ya.shape} and {yb.shape} and renders {ra.shape} "
            f"and {rb.shape}: each half needs one image per render, every (H, W, C) the same"
        )
    keep = np.ones(y.shape[1:3], bool) if mask is None else np.asarray(mask, dtype=bool)
    if keep.shape != y.shape[1:3]:
        raise ValueError(f"mask shape {keep.shape} differs from the images' {y.shape[1:3]}")
    for a in (y, ya, yb, ra, rb):
        keep = keep & np.isfinite(a).all(axis=(0, -1))
    nan = float("nan")
    result = dict.fromkeys(RESULT_KEYS, nan)
    result.update(n_pixels=int(keep.sum()), n_images=n, reason="")
    if not keep.any():
        result["reason"] = "no pixel of the region is finite in every image and render"
        return result
    y, ya, yb, ra, rb = (a[:, keep] for a in (y, ya, yb, ra, rb))  # (., P, C)
    raw = np.concatenate([ra, rb])
    mean_raw = raw.mean(axis=0)
    var = raw.var(axis=0, ddof=1)
    ybar, ybar_a, ybar_b, r_a, r_b = (a.mean(axis=0) for a in (y, ya, yb, ra, rb))
    within = ((y - ybar) ** 2).mean(axis=0)
    kappa = 0.5 - (1.0 / n) / (1.0 / m_a + 1.0 / m_b)
    cross = 0.5 * ((ybar_a - r_b) ** 2 + (ybar_b - r_a) ** 2) - kappa * (ybar_a - ybar_b) ** 2
    noise = 0.5 * var * (1.0 / m_a + 1.0 / m_b)
    per_entry = within + cross - noise  # (P, C)
    weight = 1.0 / (mean_raw * mean_raw + epsilon)
    mse = float(per_entry.mean())
    result.update(
        mse=mse,
        mse_raw=float((within + cross).mean()),
        reference_noise=float(noise.mean()),
        relative_mse=float((per_entry * weight).mean()),
        bias=float((ybar - mean_raw).mean()),
        reference_mean=float(mean_raw.mean()),
    )
    return _finish(result, mse, peak)


def _finish(result: dict, mse: float, peak: float) -> dict:
    """``result`` with its relative bias (bias over the reference mean) and its PSNR, or the
    reason there is none (an MSE not above the reference's noise)."""
    mean_r = result["reference_mean"]
    result["relative_bias"] = result["bias"] / mean_r if mean_r != 0 else math.nan
    if mse > 0:
        result["psnr"] = 10.0 * math.log10(float(peak) ** 2 / mse)
    else:
        result["reason"] = NOT_ABOVE_NOISE
    return result


def _as_stack(values, name: str) -> np.ndarray:
    a = np.asarray(values, dtype=np.float64)
    if a.ndim != 4:
        raise ValueError(f"{name} must have shape (n, H, W, C), got {a.shape}")
    return a
