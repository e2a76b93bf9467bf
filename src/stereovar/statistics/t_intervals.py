"""Student-t intervals of a mean over scenes: of values, and of ratios on the log scale.

:func:`t_interval` is the interval of a mean over scenes where each scene gives one value
(Table 3's effects, image quality, the seed-subset change); :func:`geometric_t_interval` is
its counterpart for positive ratios (a geometric mean, symmetric in a ratio and its inverse).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import stdtrit


def t_interval(values, *, level: float = 0.95) -> tuple[float, float, float]:
    """Mean of the finite values and its Student-t interval at ``level`` (95%; NaN below 2
    values)."""
    v = np.asarray([float(x) for x in values], dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return math.nan, math.nan, math.nan
    mean = float(v.mean())
    if v.size < 2:
        return mean, math.nan, math.nan
    half = float(stdtrit(v.size - 1, 0.5 + level / 2) * v.std(ddof=1) / math.sqrt(v.size))
    return mean, mean - half, mean + half


def geometric_t_interval(ratios, *, level: float = 0.95) -> tuple[float, float, float]:
    """Geometric mean of positive ratios and its interval (95%) from their logarithms.

    .. math::

        \\bar\\ell = \\frac1S \\sum_s \\log r_s, \\qquad
        \\exp\\bar\\ell, \\quad
        \\exp\\!\\left(\\bar\\ell \\pm t_{0.975,\\,S-1}\\,\\frac{s_\\ell}{\\sqrt S}\\right)

    (:func:`t_interval` of the logs, exponentiated): never below 0, and symmetric in a ratio
    and its inverse. Equal ratios give that ratio with a zero-width interval, exactly (no
    log and exp round trip to move it by an ulp). NaN when there are none; a NaN interval
    below 2 ratios.

    Parameters
    ----------
    ratios : sequence of float
        Per-scene ratios, each finite and > 0.
    level : float, keyword-only
        The interval's level (the quantile :math:`t_{(1+\\gamma)/2,\\,S-1}`).

    Raises
    ------
    ValueError
        If a ratio is not finite or not positive (it has no logarithm).
    """
    r = np.asarray([float(x) for x in ratios], dtype=np.float64)
    bad = r[~(np.isfinite(r) & (r > 0))]
    if bad.size:
        raise ValueError(f"ratio {bad[0]!r} has no logarithm; every ratio must be finite and > 0")
    if r.size >= 2 and np.all(r == r[0]):
        return float(r[0]), float(r[0]), float(r[0])
    mean, low, high = t_interval(np.log(r), level=level)
    return math.exp(mean), math.exp(low), math.exp(high)
