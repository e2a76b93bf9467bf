"""The variance-matching cost's lift over chance, with an interval that sees neighbours.

:math:`C_\\sigma` (paper Sec. 3.4) matches the two views' Eq. 1 variance fields with a
windowed SAD. Its winner-take-all accuracy minus the chance level is what the audit reads as
"a matching cue": how much more often than chance the variance alone finds the true
disparity. Neighbouring pixels share most of their window, so their hits are far from
independent and a binomial interval over pixels is much too narrow; the interval here is the
spatial block bootstrap of :mod:`stereovar.statistics.bootstrap`, over the same tiles as the
correlations'.

The lift is compared with the same lift on the matched null's frames (camera-law noise drawn
through the data's own pipeline, :mod:`stereovar.calibration`), never with a fixed camera:
an 8-bit encoding or a lens-shading gain gives both views a variance structure that a cost
can match on, and only a null drawn through that pipeline carries it too.
"""

from __future__ import annotations

import math

import numpy as np

LIFT_METHOD = "c_sigma_lift"
"""The calibration's ``method`` (and the intervention's ``metric``) of the lift."""

DISPARITY_MARGIN = 4
"""Pixels added to the largest ground-truth disparity when none is given (as
``intervention.disparity_margin``)."""


def max_disparity_of(disparity, valid, margin: int = DISPARITY_MARGIN) -> int:
    """:math:`D = \\lceil \\max d_{GT} \\rceil + m` over the valid pixels (``margin`` when
    none is valid), as the intervention scans.

    Examples
    --------
    >>> max_disparity_of(np.array([[1.2, 7.0]]), np.array([[True, False]]))
    6
    """
    d = np.asarray(disparity, dtype=np.float64)[np.asarray(valid, dtype=bool)]
    d = d[np.isfinite(d)]
    largest = float(d.max()) if d.size else 0.0
    return int(math.ceil(largest)) + int(margin)


def pixel_lift(scan, d_gt, mask) -> tuple[np.ndarray, np.ndarray]:
    """Per scoreable pixel of ``mask``, the hit minus its chance level.

    .. math::

        u(x) = \\mathbf 1\\bigl[|\\hat d(x) - d_{GT}(x)| < 1\\bigr]
            - \\frac{n_{\\text{near}}(x)}{n_{\\text{scored}}(x)}

    (Sec. 3.4; the mean of :math:`u` is ``wta_accuracy`` minus ``chance`` of
    :func:`~stereovar.intervention.scan.scan_hit_rate`).

    Returns
    -------
    u : numpy.ndarray, shape (n,)
    where : tuple of numpy.ndarray
        The pixels' (y, x) indices.
    """
    g = np.asarray(d_gt, dtype=np.float64)
    keep = np.asarray(mask, dtype=bool) & np.isfinite(g) & (scan.n_near > 0)
    hits = np.abs(scan.disparity[keep] - g[keep]) < 1.0
    chance = scan.n_near[keep] / scan.n_scored[keep]
    return hits - chance, np.nonzero(keep)


def wta_lift(
    variance_left,
    variance_right,
    ground_truth_left,
    *,
    sign: int,
    max_disparity: int | None = None,
    window: int = 5,
    tile: int = 16,
    reps: int = 1000,
    seed=0,
) -> dict:
    """:math:`C_\\sigma`'s winner-take-all accuracy minus chance over the valid set, with its
    95% tile-bootstrap interval.

    .. math::

        \\ell = \\frac1n \\sum_{x \\in \\Omega} u(x), \\qquad
        \\ell_r = \\frac{\\sum_t c_{rt} U_t}{\\sum_t c_{rt} n_t}

    with :math:`u` of :func:`pixel_lift`, :math:`U_t` and :math:`n_t` its sum and count over
    tile :math:`t`, and :math:`c_{rt}` the draw counts of replicate :math:`r`
    (:func:`~stereovar.statistics.bootstrap.draw_counts`); the interval is the replicates'
    2.5% and 97.5% quantiles.

    Parameters
    ----------
    variance_left, variance_right : array_like, shape (H, W)
        Each view's Eq. 1 field in its own coordinates (RGB-averaged).
    ground_truth_left : mapping
        ``disparity`` (subpixel magnitude) and ``valid`` of the left view.
    sign : {1, -1}
    max_disparity : int, optional
        :math:`D`; :func:`max_disparity_of` when None.
    window : int
        :math:`C_\\sigma`'s patch side.
    tile, reps, seed
        The bootstrap's tile side, replicates and seed (``analysis.bootstrap``).

    Returns
    -------
    dict
        ``value``, ``low``, ``high``, ``chance`` (mean chance level) and ``n_pixels``; NaN
        with ``n_pixels`` 0 when no pixel is scoreable.

    Examples
    --------
    Two identical variance fields with a random texture, shifted by 2 px: the cost finds
    every disparity, so the accuracy is 1 at every pixel and the lift is 1 minus the chance
    of hitting within 1 px (one of the 7 disparities 0-6, fewer scored near the border). An
    unrelated left field finds nothing beyond chance, and its interval holds 0:

    >>> rng = np.random.default_rng(0)
    >>> right = rng.random((40, 60))
    >>> left = np.roll(right, 2, axis=1)
    >>> gt = {"disparity": np.full((40, 60), 2.0), "valid": np.ones((40, 60), bool)}
    >>> r = wta_lift(left, right, gt, sign=-1, max_disparity=6, tile=8, reps=200)
    >>> round(r["value"] + r["chance"], 12), 1 / 7 <= r["chance"] < 1 / 6
    (1.0, True)
    >>> r = wta_lift(rng.random((40, 60)), right, gt, sign=-1, max_disparity=6, tile=8,
    ...              reps=200)
    >>> bool(r["low"] < 0 < r["high"])
    True
    """
    from ..statistics.bootstrap import (
        draw_counts,
        percentile_interval,
        tile_labels,
    )
    from ..statistics.regions import valid_set
    from .scan import scan_cost_volume

    d_gt = np.asarray(ground_truth_left["disparity"], dtype=np.float64)
    valid = np.asarray(ground_truth_left["valid"], dtype=bool)
    if max_disparity is None:
        max_disparity = max_disparity_of(d_gt, valid)
    omega = valid_set(d_gt, sign=sign, valid=valid)
    scan = scan_cost_volume(
        np.asarray(variance_left, dtype=np.float64),
        np.asarray(variance_right, dtype=np.float64),
        max_disparity=int(max_disparity), window=int(window), sign=int(sign), d_gt=d_gt,
    )
    u, (ys, xs) = pixel_lift(scan, d_gt, omega)
    if u.size == 0:
        return {"value": math.nan, "low": math.nan, "high": math.nan, "chance": math.nan,
                "n_pixels": 0}
    chance = float(np.mean(scan.n_near[ys, xs] / scan.n_scored[ys, xs]))
    labels = tile_labels(d_gt.shape, tile)[ys, xs]
    _, index = np.unique(labels, return_inverse=True)
    sums = np.bincount(index, weights=u)
    counts = np.bincount(index).astype(np.float64)
    low = high = math.nan
    if sums.size >= 2:
        draws = draw_counts(sums.size, int(reps), seed)
        low, high = percentile_interval((draws @ sums) / (draws @ counts))
    return {"value": float(u.mean()), "low": low, "high": high, "chance": chance,
            "n_pixels": int(u.size)}
