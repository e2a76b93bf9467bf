"""The cross-view residual correlation: do the two views' per-seed noise draws line up?

The paper's statistic (Eq. 3) correlates the two views' *variance fields*. A render-time
policy can couple the noise draws themselves: with the same sampler seed in both views
(Cycles' default seed 0, which Kubric, BlenderProc and Infinigen never change; Mitsuba's
``seed=0``, whose per-pixel stream depends only on the pixel index), the residual
:math:`\\epsilon^{(n)} = I^{(n)} - \\bar I` of seed :math:`n` in the left view repeats in the
right view, at the same pixel coordinates or at the corresponding scene point. This module
measures that directly, for every run, transformed or not: independent seeds give
:math:`\\rho_\\epsilon \\approx 0`; identical views rendered with shared seeds give 1.
"""

from __future__ import annotations

import numpy as np

from .bootstrap import (
    FEWER_THAN_2_TILES,
    BootstrapSettings,
    bootstrap_replicates,
    draw_counts,
    pearson_from_sums,
    percentile_interval,
    tile_labels,
    tile_sums,
)
from .correlation import CONSTANT
from .regions import as_field
from .warp import WarpPlan, warp_finite

ALIGNMENTS = ("ground_truth", "zero")
"""``ground_truth``: the right residual sampled at :math:`x + s\\,d(x)` (Eq. 2); ``zero``: at
the same pixel coordinates (what a shared seed couples)."""

RESULT_KEYS = ("rho", "low", "high", "n_pixels", "n_seeds", "n_tiles", "reason")
"""What :func:`residual_correlation` gives per region and alignment, beside ``region`` and
``alignment``."""

MIN_PIXELS = 30
"""Fewest left pixels for a defined correlation (as :func:`~stereovar.statistics.correlation.
pearson_over_mask`'s default)."""


def seed_residuals(stack) -> tuple[np.ndarray, np.ndarray]:
    """Per-seed residuals from the seed mean, averaged over channels (as Eq. 1 averages).

    .. math::

        \\epsilon^{(n)}(x, y) = \\frac1C \\sum_c \\Bigl(I_c^{(n)}(x, y) - \\bar I_c(x, y)\\Bigr),
        \\qquad \\bar I_c = \\frac1N \\sum_n I_c^{(n)}

    (the decomposition :math:`I^{(n)} = \\bar I + \\epsilon^{(n)}` of Sec. 3.4).

    Parameters
    ----------
    stack : array_like, shape (N, H, W, C) or (N, H, W)
        The :math:`N` renders of one view.

    Returns
    -------
    residuals : numpy.ndarray, float64 (N, H, W)
        0 where ``finite`` is False.
    finite : numpy.ndarray of bool (H, W)
        Every seed and channel is finite at the pixel.
    """
    values = np.asarray(stack)
    if values.ndim == 4:
        values = values.mean(axis=-1, dtype=np.float64)
    elif values.ndim != 3:
        raise ValueError(f"renders must have shape (N, H, W, C) or (N, H, W), got {values.shape}")
    values = np.asarray(values, dtype=np.float64)
    if values.shape[0] < 2:
        raise ValueError(f"residuals need at least 2 seeds, got {values.shape[0]}")
    finite = np.isfinite(values).all(axis=0)
    if not finite.all():
        values = np.where(finite, values, 0.0)
    residuals = values - values.mean(axis=0)
    return residuals, finite


def _result(n_pixels: int, n_seeds: int, reason: str) -> dict:
    nan = float("nan")
    return {
        "rho": nan,
        "low": nan,
        "high": nan,
        "n_pixels": int(n_pixels),
        "n_seeds": int(n_seeds),
        "n_tiles": 0,
        "reason": reason,
    }


def pooled_correlation(
    a, b, labels, *, settings: BootstrapSettings, min_pixels: int = MIN_PIXELS
) -> dict:
    """Pearson's :math:`\\rho` of seed-by-pixel pairs pooled over seeds, with its spatial
    block-bootstrap interval.

    .. math::

        \\rho_\\epsilon = \\frac{\\sum_{n, p} (a_{np} - \\bar a)(b_{np} - \\bar b)}
            {\\sqrt{\\sum_{n, p} (a_{np} - \\bar a)^2 \\sum_{n, p} (b_{np} - \\bar b)^2}}

    over seeds :math:`n` and pixels :math:`p`. The bootstrap resamples tiles
    (:mod:`~stereovar.statistics.bootstrap`); a tile carries every seed of its pixels, so the
    dependence between seeds at one pixel stays inside it.

    Parameters
    ----------
    a, b : numpy.ndarray, shape (N, n)
        The paired residuals: seed by pixel.
    labels : numpy.ndarray of int, shape (n,)
        Bootstrap tile of each pixel.
    settings : BootstrapSettings, keyword-only
    min_pixels : int, keyword-only

    Returns
    -------
    dict
        :data:`RESULT_KEYS`.
    """
    n_seeds, n = a.shape
    if n < min_pixels:
        return _result(n, n_seeds, f"fewer than {min_pixels} valid pixels (n={n})")
    order = np.argsort(labels, kind="stable")
    # pixel-major, seeds inside: tile labels stay sorted for product_sums' fast path
    av = a[:, order].T.ravel()
    bv = b[:, order].T.ravel()
    tiles = np.repeat(labels[order], n_seeds)
    if av.min() == av.max() or bv.min() == bv.max():
        return _result(n, n_seeds, CONSTANT)
    sums = tile_sums(av, bv, tiles)
    rho = float(pearson_from_sums(sums.sum(axis=0)))
    result = _result(n, n_seeds, "")
    if not np.isfinite(rho):
        result["reason"] = CONSTANT
        return result
    result["rho"] = rho
    result["n_tiles"] = int(sums.shape[0])
    if sums.shape[0] < 2:
        result["reason"] = FEWER_THAN_2_TILES
        return result
    reps = bootstrap_replicates(sums, draw_counts(sums.shape[0], settings.reps, settings.seed))
    result["low"], result["high"] = percentile_interval(reps)
    return result


def residual_correlation(
    left,
    right,
    disparity,
    *,
    sign: int,
    masks: dict,
    valid=None,
    alignments=ALIGNMENTS,
    settings: BootstrapSettings | None = None,
    min_pixels: int = MIN_PIXELS,
) -> list[dict]:
    """The cross-view correlation of per-seed residuals, at the ground-truth alignment and at
    zero disparity, per region.

    With :math:`\\epsilon_V^{(n)}` the channel-averaged residual of seed :math:`n` in view
    :math:`V` (:func:`seed_residuals`), over the left pixels :math:`p` of a region and the
    :math:`N` seeds,

    .. math::

        \\rho_\\epsilon^{\\text{GT}} = \\operatorname{corr}_{n, p}\\Bigl(
            \\epsilon_L^{(n)}(x_p, y_p),\\ \\epsilon_R^{(n)}\\bigl(x_p + s\\,d(x_p, y_p), y_p\\bigr)
            \\Bigr), \\qquad
        \\rho_\\epsilon^{0} = \\operatorname{corr}_{n, p}\\Bigl(
            \\epsilon_L^{(n)}(x_p, y_p),\\ \\epsilon_R^{(n)}(x_p, y_p)\\Bigr),

    seed :math:`n` of the left view paired with seed :math:`n` of the right, the right residual
    sampled by Eq. 2's bilinear warp (Sec. 2.2; :class:`~stereovar.statistics.warp.WarpPlan`),
    and Pearson's :math:`\\rho` pooled over seeds and pixels
    (:func:`pooled_correlation`), with a spatial block-bootstrap 95% interval.

    Pixels used: the region's mask, where every left seed is finite; at the ground-truth
    alignment also inside the warp's geometric valid set and with no non-finite right pixel
    among the bilinear taps (:func:`~stereovar.statistics.warp.warp_finite`); at zero
    disparity also where every right seed is finite at the same pixel.

    Parameters
    ----------
    left, right : array_like, shape (N, H, W, C) or (N, H, W)
        The two views' :math:`N` renders, seed :math:`n` of one paired with seed :math:`n` of
        the other.
    disparity : array_like, shape (H, W)
        Left-view disparity magnitude in pixels (the ground truth's).
    sign : {1, -1}, keyword-only
        The ground truth's ``disparity_sign``.
    masks : dict of str to array_like of bool (H, W), keyword-only
        Left-view regions (:func:`~stereovar.statistics.regions.region_masks`).
    valid : array_like of bool (H, W), keyword-only, optional
        The ground truth's left ``valid``.
    alignments : sequence of str, keyword-only
        Some of :data:`ALIGNMENTS`.
    settings : BootstrapSettings, keyword-only, optional
        Tile, replicates and seed (``analysis.bootstrap``).
    min_pixels : int, keyword-only
        Fewest pixels for a defined result.

    Returns
    -------
    list of dict
        One row per region and alignment, in that order: ``region``, ``alignment`` and
        :data:`RESULT_KEYS` (``rho``, the interval ``low`` and ``high``, ``n_pixels`` the left
        pixels used, ``n_seeds``, ``n_tiles``, and ``reason``: ``""``, or why the numbers are
        NaN: too few pixels, a constant residual, fewer than 2 tiles for an interval).
    """
    settings = settings or BootstrapSettings()
    unknown = [a for a in alignments if a not in ALIGNMENTS]
    if unknown:
        raise ValueError(f"unknown alignments {unknown}; use some of {ALIGNMENTS}")
    eps_left, finite_left = seed_residuals(left)
    eps_right, finite_right = seed_residuals(right)
    if eps_left.shape != eps_right.shape:
        raise ValueError(
            f"left renders {eps_left.shape} and right renders {eps_right.shape} differ in "
            "(N, H, W); pair seed n of one view with seed n of the other"
        )
    shape = eps_left.shape[1:]
    d = as_field(disparity)
    if d.shape != shape:
        raise ValueError(f"disparity shape {d.shape} does not match the renders' {shape}")
    labels = tile_labels(shape, settings.tile).ravel()
    plan = None
    rows = []
    for region, mask in masks.items():
        mask = as_field(mask).astype(bool)
        if mask.shape != shape:
            raise ValueError(f"region {region!r} mask shape {mask.shape} differs from {shape}")
        for alignment in alignments:
            if alignment == "ground_truth":
                if plan is None:
                    plan = WarpPlan(d, sign=sign, valid=valid)
                    _, omega, clean = warp_finite(
                        np.where(finite_right, 0.0, np.nan), d, sign=sign, valid=valid, plan=plan
                    )
                    usable_gt = omega & clean & finite_left
                pixels = np.flatnonzero(mask & usable_gt)
                b = plan.sample(eps_right, pixels)
            else:
                pixels = np.flatnonzero(mask & finite_left & finite_right)
                b = eps_right.reshape(eps_right.shape[0], -1)[:, pixels]
            a = eps_left.reshape(eps_left.shape[0], -1)[:, pixels]
            result = pooled_correlation(
                a, b, labels[pixels], settings=settings, min_pixels=min_pixels
            )
            rows.append({"region": region, "alignment": alignment, **result})
    return rows
