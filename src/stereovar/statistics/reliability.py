"""Estimator reliability and the attenuation of :math:`\\rho` by finite :math:`N`.

Eq. 1 estimates each view's variance field from :math:`N` seeds, so each field is the true
field plus estimator noise that is independent between views. Independent noise attenuates a
correlation (Spearman 1904): with reliabilities :math:`r_L, r_R` (the share of a field's
spread that is not estimator noise),

.. math:: \\rho_{\\text{observed}} = \\rho_{\\text{true}} \\sqrt{r_L r_R}.

The reliability of an :math:`N`-seed field is measured by splitting the seeds into two halves
(even and odd indices, :mod:`stereovar.estimators.subsets`), correlating the two
:math:`N/2`-seed fields of one view, and stepping that up to :math:`N` with the
Spearman-Brown formula.
"""

from __future__ import annotations

import math

import numpy as np

TOO_FEW_SEEDS = "split-half needs at least 4 seeds (two halves of 2)"
CORRECTED_ABOVE_1 = "attenuation-corrected rho above 1"


def spearman_brown(r_half: float, factor: float = 2.0) -> float:
    """Reliability of an estimate ``factor`` times longer than one of reliability ``r_half``.

    .. math:: r_N = \\frac{k\\, r_{N/k}}{1 + (k - 1)\\, r_{N/k}}, \\qquad k = 2

    NaN for a non-finite input; a negative split-half correlation is returned as computed
    (the fields carry no reliable structure).
    """
    r = float(r_half)
    if not math.isfinite(r):
        return float("nan")
    denominator = 1.0 + (factor - 1.0) * r
    return float("nan") if denominator == 0 else factor * r / denominator


def attenuation_corrected(rho: float, reliability_left: float, reliability_right: float):
    """Disattenuated correlation :math:`\\rho / \\sqrt{r_L r_R}` and whether it exceeds 1.

    .. math:: \\rho_{\\text{corrected}} = \\frac{\\rho}{\\sqrt{r_L\\, r_R}}

    Returned as computed (values above 1 occur when the reliabilities are themselves noisy
    estimates); NaN unless both reliabilities are positive.

    Returns
    -------
    corrected : float
    above_one : bool
    """
    rl, rr = float(reliability_left), float(reliability_right)
    if not (rl > 0 and rr > 0) or not math.isfinite(float(rho)):
        return float("nan"), False
    corrected = float(rho) / math.sqrt(rl * rr)
    return corrected, bool(abs(corrected) > 1.0)


def curve_summary(values) -> dict:
    """Mean, sample standard deviation (ddof 1) and count of the finite values."""
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    return {
        "mean_rho": float(v.mean()) if v.size else float("nan"),
        "std_rho": float(v.std(ddof=1)) if v.size > 1 else float("nan"),
        "n_subsets": int(v.size),
    }


def corrected_interval(row: dict, *, bounded: bool = True) -> tuple[float, float]:
    """The interval of a correlation row's attenuation-corrected :math:`\\rho`: its bootstrap
    interval divided by :math:`\\sqrt{r_L r_R}` (the reliabilities held fixed), cut to
    :math:`[-1, 1]`.

    .. math::

        \\Bigl[\\max\\Bigl(-1, \\frac{\\ell}{\\sqrt{r_L r_R}}\\Bigr),\\
            \\min\\Bigl(1, \\frac{h}{\\sqrt{r_L r_R}}\\Bigr)\\Bigr]

    The corrected :math:`\\rho` estimates a correlation, which lies in :math:`[-1, 1]`, so the
    interval is intersected with :math:`[-1, 1]`: the intersection covers the true value
    whenever the divided interval does (the true value is never outside), so it keeps the
    interval's coverage. The interval is cut rather than formed on Fisher's :math:`z`: the
    corrected value is a ratio, not a sample correlation, and can itself exceed 1 when the
    reliabilities are noisy estimates (flagged by :data:`CORRECTED_ABOVE_1`), where it has no
    :math:`z`. An interval wholly above 1 becomes the point 1 (wholly below -1, -1): the
    reliabilities are then inconsistent with the observed :math:`\\rho`, and the point
    estimate is flagged.

    Parameters
    ----------
    row : dict
        A correlation row (``boot_low``, ``boot_high``, ``reliability_left``,
        ``reliability_right``, ``rho_corrected``).
    bounded : bool, keyword-only
        False: the divided interval uncut (for combining over scenes before cutting, as
        :func:`stereovar.audit.verdict.correlation_summary` does: cut intervals are shorter
        and would understate each scene's error).

    Returns
    -------
    low, high : float
        NaN where the row has no corrected :math:`\\rho`.

    Examples
    --------
    >>> row = {"rho": 0.9, "boot_low": 0.8, "boot_high": 0.95, "reliability_left": 0.9,
    ...        "reliability_right": 0.9, "rho_corrected": 1.0}
    >>> [round(v, 3) for v in corrected_interval(row, bounded=False)]
    [0.889, 1.056]
    >>> [round(v, 3) for v in corrected_interval(row)]
    [0.889, 1.0]
    """
    r = row.get("reliability_left", math.nan) * row.get("reliability_right", math.nan)
    if not r > 0 or not math.isfinite(row.get("rho_corrected", math.nan)):
        return math.nan, math.nan
    low, high = row["boot_low"] / math.sqrt(r), row["boot_high"] / math.sqrt(r)
    if not bounded:
        return low, high
    return min(max(low, -1.0), 1.0), min(max(high, -1.0), 1.0)
