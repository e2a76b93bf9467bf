"""Agreement of two estimates of the same variance field (the estimator validation).

The ``moments`` estimator (:mod:`stereovar.estimators.moments`) and Eq. 1 over :math:`N`
seeds (paper Sec. 2.1) estimate the same per-pixel quantity, the variance of a pixel at
:math:`s` samples. :func:`field_agreement` measures how closely one view's two estimates
agree: the ratio of their mean levels with a spatial block-bootstrap interval, and their
rank (Spearman) and Pearson correlations over the pixels where both are defined. The
reference's own split-half reliability (:func:`split_half_reliability`) says how much of
the disagreement is the reference's noise.
"""

from __future__ import annotations

import numpy as np

from .bootstrap import BootstrapSettings, draw_counts, percentile_interval, tile_labels
from .reliability import spearman_brown

AGREEMENT_KEYS = ("n_pixels", "mean_ratio", "ratio_low", "ratio_high", "spearman", "pearson")
"""Keys of :func:`field_agreement`."""


def mean_ratio(a, b, labels, *, settings: BootstrapSettings | None = None, seed=0):
    """Ratio of mean levels :math:`\\bar a / \\bar b` with a block-bootstrap interval.

    .. math::

        R = \\frac{\\sum_i a_i}{\\sum_i b_i}, \\qquad
        R^{*}_r = \\frac{\\sum_t c_{rt} A_t}{\\sum_t c_{rt} B_t},

    with :math:`A_t`, :math:`B_t` the sums over tile :math:`t` and :math:`c_{rt}` how often
    replicate :math:`r` draws the tile (:func:`~stereovar.statistics.bootstrap.draw_counts`);
    the interval is the percentile interval of the :math:`R^*_r`.

    Parameters
    ----------
    a, b : numpy.ndarray, shape (n,)
        Paired finite values.
    labels : numpy.ndarray of int, shape (n,)
        Tile index of each pair.
    settings : BootstrapSettings, keyword-only
    seed : keyword-only
        Seed of the tile draws.

    Returns
    -------
    ratio, low, high : float
    """
    settings = settings or BootstrapSettings()
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    if a.size == 0 or not b.sum() > 0:
        return float("nan"), float("nan"), float("nan")
    _, tiles = np.unique(labels, return_inverse=True)
    sums_a = np.bincount(tiles, weights=a)
    sums_b = np.bincount(tiles, weights=b)
    counts = draw_counts(len(sums_a), settings.reps, seed)
    with np.errstate(divide="ignore", invalid="ignore"):
        replicates = (counts @ sums_a) / (counts @ sums_b)
    low, high = percentile_interval(replicates)
    return float(a.sum() / b.sum()), low, high


def field_agreement(
    estimate, reference, mask, *, settings: BootstrapSettings | None = None, seed=0
) -> dict:
    """How one view's variance estimate agrees with a reference estimate of the same field.

    Over the pixels of ``mask`` where both fields are finite: the mean-level ratio
    estimate / reference with its block-bootstrap interval (:func:`mean_ratio`), and the
    Spearman and Pearson correlations of the two fields (``scipy.stats``).

    Parameters
    ----------
    estimate, reference : array_like, shape (H, W)
    mask : array_like of bool, shape (H, W)
    settings : BootstrapSettings, keyword-only
        Tile side and replicates of the interval.
    seed : keyword-only

    Returns
    -------
    dict
        :data:`AGREEMENT_KEYS`.
    """
    from scipy import stats  # only the estimator checks pay its import

    settings = settings or BootstrapSettings()
    a = np.asarray(estimate, np.float64)
    b = np.asarray(reference, np.float64)
    keep = np.asarray(mask, bool) & np.isfinite(a) & np.isfinite(b)
    labels = tile_labels(a.shape, settings.tile)[keep]
    x, y = a[keep], b[keep]
    ratio, low, high = mean_ratio(x, y, labels, settings=settings, seed=seed)
    defined = x.size >= 3 and np.ptp(x) > 0 and np.ptp(y) > 0
    return {
        "n_pixels": int(x.size),
        "mean_ratio": ratio,
        "ratio_low": low,
        "ratio_high": high,
        "spearman": float(stats.spearmanr(x, y).statistic) if defined else float("nan"),
        "pearson": float(stats.pearsonr(x, y).statistic) if defined else float("nan"),
    }


def split_half_reliability(halves, mask) -> dict:
    """Reliability of an estimate from the agreement of its two independent halves.

    .. math::

        r = \\frac{2 r_{1/2}}{1 + r_{1/2}}

    (Spearman-Brown, :func:`~stereovar.statistics.reliability.spearman_brown`) of the
    Spearman and the Pearson correlation :math:`r_{1/2}` of the half fields over ``mask``.

    Parameters
    ----------
    halves : array_like, shape (2, H, W)
    mask : array_like of bool, shape (H, W)

    Returns
    -------
    dict
        ``reliability_spearman``, ``reliability_pearson``.
    """
    from scipy import stats  # only the estimator checks pay its import

    h = np.asarray(halves, np.float64)
    keep = np.asarray(mask, bool) & np.isfinite(h).all(axis=0)
    x, y = h[0][keep], h[1][keep]
    if x.size < 3 or not (np.ptp(x) > 0 and np.ptp(y) > 0):
        return {"reliability_spearman": float("nan"), "reliability_pearson": float("nan")}
    return {
        "reliability_spearman": spearman_brown(stats.spearmanr(x, y).statistic),
        "reliability_pearson": spearman_brown(stats.pearsonr(x, y).statistic),
    }
