"""Rates with their 95% Wilson interval, and the level, coverage and power they are held to.

A rate is a share :math:`k/n` of replicates with its 95% Wilson interval (:func:`rate`). A
rate held to the 5% level (:data:`LEVEL`) ``meets_target`` (:func:`meets_level`) only when
its whole interval does: ``yes`` when the upper bound is at most 5%, ``no`` when the lower
bound is above it (refuted), and ``not shown`` when the interval straddles it (too few
replicates to show the level: with no false positive that takes :func:`replicates_to_show`,
73). A coverage is held to 95 +/- 2% (:data:`COVERAGE_TARGET`), and a planted strength counts
as detectable from 80% power on (:data:`POWER`, :func:`detectable`).
"""

from __future__ import annotations

import math

from scipy.special import ndtri

LEVEL = 0.05
"""The level every rule is held to: at most 5% false positives."""

COVERAGE_TARGET = (0.93, 0.97)
"""A 95% interval's coverage must lie within 95 +/- 2%."""

POWER = 0.8
"""The power at which a strength counts as detectable."""

Z = float(ndtri(0.975))
"""The normal quantile :math:`z_{0.975}` of a two-sided 95% interval."""

NOT_SHOWN = "not shown"
"""``meets_target`` of a rate whose Wilson interval straddles its level: neither shown nor
refuted, too few replicates to tell."""


def _f(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def rate(k: int, n: int) -> tuple[float, float, float]:
    """A proportion :math:`k/n` with its 95% Wilson interval (NaN for :math:`n = 0`).

    Examples
    --------
    >>> [round(x, 3) for x in rate(5, 100)]
    [0.05, 0.022, 0.112]
    """
    if n <= 0:
        return math.nan, math.nan, math.nan
    from scipy import stats  # binomtest: imported by the jobs that count

    ci = stats.binomtest(int(k), int(n)).proportion_ci(confidence_level=0.95, method="wilson")
    return k / n, float(ci.low), float(ci.high)


def meets_level(low, high, level: float = LEVEL) -> str:
    """Whether a rate held to at most ``level`` is shown to meet it, from its 95% Wilson
    interval :math:`[\\ell, h]`: ``yes`` when the whole interval does (:math:`h \\le` level),
    ``no`` when it lies above (:math:`\\ell >` level: refuted), :data:`NOT_SHOWN` when it
    straddles the level, ``""`` when it is not known.

    Examples
    --------
    >>> [meets_level(*rate(k, n)[1:]) for k, n in ((0, 80), (0, 16), (10, 20))]
    ['yes', 'not shown', 'no']
    """
    low, high = _f(low), _f(high)
    if not (math.isfinite(low) and math.isfinite(high)):
        return ""
    if high <= level:
        return "yes"
    if low > level:
        return "no"
    return NOT_SHOWN


def replicates_to_show(level: float = LEVEL) -> int:
    """The fewest replicates that can show a rate of at most ``level``: the smallest
    :math:`n` whose Wilson upper bound with no false positive, :math:`z^2/(n + z^2)`, is at
    most ``level`` (more are needed when any replicate fires).

    Examples
    --------
    >>> replicates_to_show()
    73
    """
    n = max(1, math.floor(Z * Z * (1 - level) / level) - 1)
    while rate(0, n)[2] > level:
        n += 1
    return n


def _meets_rate(r) -> str:
    """:func:`meets_level` of a :func:`rate` against :data:`LEVEL`."""
    return meets_level(r[1], r[2])


def _meets_coverage(r) -> str:
    """``yes`` when the coverage's Wilson interval meets 95 +/- 2%, ``no`` when it lies
    outside, ``short`` when it lies below."""
    low, high = COVERAGE_TARGET
    if not math.isfinite(r[1]):
        return ""
    if r[2] < low:
        return "short"
    if r[1] > high:
        return "over"
    return "yes"


def detectable(power_curve: list[tuple[float, float]], target: float = POWER) -> float:
    """The smallest strength whose power reaches ``target``, linearly interpolated between
    the grid's strengths (NaN when none does).

    Examples
    --------
    >>> detectable([(0.25, 0.1), (0.5, 0.5), (1.0, 0.9)])
    0.875
    """
    prev = None
    for s, p in sorted(power_curve):
        if math.isfinite(p) and p >= target:
            if prev is None or not math.isfinite(prev[1]):
                return float(s)
            s0, p0 = prev
            if p == p0:
                return float(s)
            return float(s0 + (target - p0) * (s - s0) / (p - p0))
        prev = (s, p)
    return math.nan
