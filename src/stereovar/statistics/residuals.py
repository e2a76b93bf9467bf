"""The cross-view residual correlation: do the two views' per-seed noise draws line up?

The paper's statistic (Eq. 3) correlates the two views' *variance fields*. A render-time
policy can couple the noise draws themselves: with the same sampler seed in both views
(Cycles' default seed 0, which Kubric and Infinigen never change; Mitsuba's
``seed=0``, whose per-pixel stream depends only on the pixel index), the residual
:math:`\\epsilon^{(n)} = I^{(n)} - \\bar I` of seed :math:`n` in the left view repeats in the
right view, at the same pixel coordinates or at the corresponding scene point. This module
measures that directly, for every run, transformed or not: independent seeds give
:math:`\\rho_\\epsilon \\approx 0`; identical views rendered with shared seeds give 1.

Each pixel's residuals are standardised over the seeds before they are pooled
(:func:`standardised`), so every pixel weighs the same: pooling the raw residuals weights a
pixel by :math:`\\sigma_L \\sigma_R`, and one coupling of 0.5 then reads 0.51 or 0.13
depending only on where the high-variance pixels sit (``tests/test_residual_coupling.py``).
Rows come per region and, on request, per band of the ground-truth disparity
(:data:`DISPARITY_BANDS`).
"""

from __future__ import annotations

import math

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
"""What :func:`residual_correlation` gives per region, alignment and band, beside ``region``,
``alignment`` and ``band``."""

SHARED_STREAMS = 0.05
"""The views share their random streams when the per-seed residuals' cross-view correlation
at zero disparity (:func:`residual_correlation`) has a 95% interval above this (independent
seeds give 0; the same seed in both views gives the share of each pixel's noise that the two
views' paths have in common). The calibration measures how often it fires on frames whose
views are independent (``shared_streams`` in ``calibration.csv``)."""

MIN_PIXELS = 30
"""Fewest left pixels for a defined correlation (as :func:`~stereovar.statistics.correlation.
pearson_over_mask`'s default)."""

DISPARITY_BANDS = (0.0, 2.0, 8.0, math.inf)
"""Edges in pixels of the ground-truth disparity bands of :func:`residual_correlation`:
:math:`[0, 2)`, :math:`[2, 8)`, :math:`[8, \\infty)`, by the left pixel's disparity
magnitude. Below 2 px the ground-truth taps :math:`x + s\\,d` lie within a pixel of
:math:`x` (they include :math:`x` itself below 1 px, and a reconstruction filter wider than
the box, Cycles' 1.5 px Blackman-Harris or an audit's unknown one, spreads one sample over
neighbours), so a coupling at the same pixel coordinates also shows at the ground-truth
alignment there; from 8 px on the two alignments are further apart than the null-shift
control's 8 px (``controls.null_shift``). Fixed edges, unlike quantiles, mean the same on
every scene, so the rows pool across scenes. On the default run (320x180) the disparities lie
between 1 and 5 px: about half the valid pixels fall in each of the first two bands and the
third is empty (its rows say so)."""

ALL_BANDS = "all"
"""The ``band`` of the rows over every disparity."""


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
        0 where ``finite`` is False, and exactly 0 where every seed has the same value.
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
    # every seed equal: exactly 0 (the mean can differ from the value in its last bit)
    residuals[:, (values == values[0]).all(axis=0)] = 0.0
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


def standardised(residuals) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's residuals over the seeds, centred and divided by their standard deviation.

    .. math::

        z_{np} = \\frac{a_{np} - \\bar a_p}{\\hat\\sigma_p}, \\qquad
        \\hat\\sigma_p^2 = \\frac1{N-1} \\sum_n (a_{np} - \\bar a_p)^2,

    so :math:`\\sum_n z_{np} = 0` and :math:`\\sum_n z_{np}^2 = N - 1` at every pixel
    :math:`p`: the pooled Pearson of two views' :math:`z` is the mean over pixels of each
    pixel's correlation over the seeds (:func:`residual_correlation`).

    Parameters
    ----------
    residuals : array_like, shape (N, n)
        Seed by pixel.

    Returns
    -------
    z : numpy.ndarray, float64 (N, n)
        0 where ``spread`` is False.
    spread : numpy.ndarray of bool (n,)
        :math:`\\hat\\sigma_p > 0`: the pixel's residuals are not all equal (its correlation
        is defined).

    Examples
    --------
    >>> z, ok = standardised(np.array([[1.0, 5.0], [3.0, 5.0], [5.0, 5.0]]))
    >>> z[:, 0].tolist(), ok.tolist()
    ([-1.0, 0.0, 1.0], [True, False])
    """
    a = np.asarray(residuals, dtype=np.float64)
    dev = a - a.mean(axis=0)
    # all seeds equal: exactly no spread (the mean can differ from the value in its last bit)
    dev[:, (a == a[0]).all(axis=0)] = 0.0
    sd = np.sqrt((dev * dev).sum(axis=0) / (a.shape[0] - 1))
    spread = sd > 0
    return np.divide(dev, sd, out=np.zeros_like(dev), where=spread), spread


def band_label(low: float, high: float) -> str:
    """The ``band`` of the disparities in :math:`[\\text{low}, \\text{high})` px.

    Examples
    --------
    >>> band_label(0.0, 2.0), band_label(8.0, float("inf"))
    ('d0-2', 'd8-inf')
    """
    return f"d{low:g}-{high:g}"


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
    bands=None,
    settings: BootstrapSettings | None = None,
    min_pixels: int = MIN_PIXELS,
) -> list[dict]:
    """The cross-view correlation of per-seed residuals, each pixel standardised, at the
    ground-truth alignment and at zero disparity, per region and disparity band.

    With :math:`\\epsilon_V^{(n)}` the channel-averaged residual of seed :math:`n` in view
    :math:`V` (:func:`seed_residuals`), a left pixel :math:`p` pairs

    .. math::

        a_{np} = \\epsilon_L^{(n)}(x_p, y_p), \\qquad
        b_{np}^{\\text{GT}} = \\epsilon_R^{(n)}\\bigl(x_p + s\\,d(x_p, y_p), y_p\\bigr),
        \\qquad b_{np}^{0} = \\epsilon_R^{(n)}(x_p, y_p),

    seed :math:`n` of the left view with seed :math:`n` of the right, the right residual
    sampled by Eq. 2's bilinear warp (Sec. 2.2; :class:`~stereovar.statistics.warp.WarpPlan`).
    Each pixel's :math:`a` and :math:`b` are standardised over the :math:`N` seeds
    (:func:`standardised`) and Pearson's :math:`\\rho` is pooled over seeds and the
    :math:`P` pixels (:func:`pooled_correlation`, with its spatial block-bootstrap 95%
    interval), which is the mean of the pixels' own correlations:

    .. math::

        \\rho_\\epsilon = \\frac1P \\sum_p r_p, \\qquad
        r_p = \\frac{\\sum_n a_{np} b_{np}}
            {\\sqrt{\\sum_n a_{np}^2 \\sum_n b_{np}^2}}.

    What this measures:

    - Every pixel weighs the same. Pooling the raw residuals instead weights pixel :math:`p`
      by :math:`\\sigma_L(p)\\sigma_R(p)`, so one coupling :math:`c` reads anywhere between
      about :math:`c` (high-variance pixels at the same place in both views) and far less
      (high variance in one view where the other is quiet). :math:`r_p` does not change when
      either view's residuals at :math:`p` are scaled.
    - Independent views give :math:`\\mathrm E[r_p] = 0` exactly, for any noise law: given the
      left residuals, the right view's seeds are exchangeable, so each term of :math:`r_p`
      has mean 0.
    - The same random stream gives 1: :math:`b_{np} = k_p a_{np}` with :math:`k_p > 0`
      (shared seed, any per-pixel gain between the views) gives :math:`r_p = 1`.
    - A coupling :math:`c` between :math:`N` Gaussian residual pairs reads, on average, the
      sample correlation's mean (Fisher 1915)

      .. math::

          \\mathrm E[r_p] = c\\,
              \\frac{\\Gamma(N/2)^2}{\\Gamma\\bigl(\\tfrac{N-1}2\\bigr)
                  \\Gamma\\bigl(\\tfrac{N+1}2\\bigr)}\\,
              {}_2F_1\\bigl(\\tfrac12, \\tfrac12; \\tfrac{N+1}2; c^2\\bigr)
          \\approx c\\Bigl(1 - \\frac{1 - c^2}{2N}\\Bigr),

      slightly below :math:`c` between 0 and 1 (0.4725 for :math:`c = 0.5`, :math:`N = 8`);
      0 and 1 stay exact.

    Each pixel is scaled by the standard deviation of all :math:`N` of its seeds. A
    leave-one-out :math:`\\hat\\sigma_{-n}` (the other :math:`N - 1` seeds) was weighed and is
    not used. Its standardised residuals do not sum to 0 over the seeds: with skewed noise
    (Monte Carlo noise is right-skewed) their per-pixel mean follows the skewness, which the two
    views share, and independent views read 0.0074 (standard error 0.0006) on skewed noise
    instead of 0. Its :math:`z` has Student-t tails (a pixel whose other seeds agree gives
    :math:`\\hat\\sigma_{-n} = 0`), so on heavy-tailed noise (a mean of 4 lognormal samples,
    :math:`N = 8`, 20 000 pixels) its spread over datasets was 10 to 25 times the all-seed
    version's (0.047 against 0.0021 at a coupling of 0.5), and it attenuates more (0.455
    against 0.472 for Gaussian :math:`c = 0.5`).

    Pixels used: the region's mask, where every left seed is finite; at the ground-truth
    alignment also inside the warp's geometric valid set and with no non-finite right pixel
    among the bilinear taps (:func:`~stereovar.statistics.warp.warp_finite`); at zero
    disparity also where every right seed is finite at the same pixel; and where neither
    :math:`a` nor :math:`b` is the same for every seed (:math:`r_p` undefined). A band holds
    the pixels whose disparity magnitude :math:`d` is in :math:`[\\text{low}, \\text{high})`;
    a pixel whose disparity is not finite is in no band.

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
    bands : sequence of float, keyword-only, optional
        Increasing band edges in pixels (e.g. :data:`DISPARITY_BANDS`); None gives the rows
        over every disparity only.
    settings : BootstrapSettings, keyword-only, optional
        Tile, replicates and seed (``analysis.bootstrap``).
    min_pixels : int, keyword-only
        Fewest pixels for a defined result.

    Returns
    -------
    list of dict
        One row per region, alignment and band, in that order, band :data:`ALL_BANDS` first,
        then one per band (:func:`band_label`): ``region``, ``alignment``, ``band`` and
        :data:`RESULT_KEYS` (``rho``, the interval ``low`` and ``high``, ``n_pixels`` the left
        pixels used, ``n_seeds``, ``n_tiles``, and ``reason``: ``""``, or why the numbers are
        NaN: too few pixels, a constant residual, fewer than 2 tiles for an interval).
    """
    settings = settings or BootstrapSettings()
    unknown = [a for a in alignments if a not in ALIGNMENTS]
    if unknown:
        raise ValueError(f"unknown alignments {unknown}; use some of {ALIGNMENTS}")
    edges = [] if bands is None else [float(e) for e in bands]
    if bands is not None and (len(edges) < 2 or np.any(np.diff(edges) <= 0)):
        raise ValueError(f"bands must be at least 2 increasing edges, got {list(bands)}")
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
    magnitude = np.abs(d).ravel()
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
            za, spread_a = standardised(a)
            zb, spread_b = standardised(b)
            spread = spread_a & spread_b
            chosen = [(ALL_BANDS, np.ones(pixels.size, bool))]
            chosen += [
                (band_label(lo, hi), (magnitude[pixels] >= lo) & (magnitude[pixels] < hi))
                for lo, hi in zip(edges[:-1], edges[1:], strict=True)
            ]
            for band, inside in chosen:
                keep = inside & spread
                if not keep.any() and inside.sum() >= min_pixels:
                    result = _result(int(inside.sum()), a.shape[0], CONSTANT)
                else:
                    result = pooled_correlation(
                        za[:, keep],
                        zb[:, keep],
                        labels[pixels[keep]],
                        settings=settings,
                        min_pixels=min_pixels,
                    )
                rows.append({"region": region, "alignment": alignment, "band": band, **result})
    return rows
