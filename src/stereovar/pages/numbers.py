"""Numbers as the pages show them: a value to significant digits (:func:`significant`), a
value with its 95% interval (:func:`interval_text`).

Both the results page's tables (:mod:`stereovar.pages.results`) and the templates'
``significant`` filter (:mod:`stereovar.pages.templates`) use them; this module imports
neither.
"""

from __future__ import annotations

import math

__all__ = ["interval_text", "significant"]


def _f(value) -> float:
    """``value`` as a float; NaN where it is none (None, empty, not a number)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def significant(value: float, digits: int = 3) -> str:
    """``value`` to ``digits`` significant digits (at least), with no exponent from 0.0001 up
    to a million: a value of ``digits`` or more integer digits is shown whole.

    Examples
    --------
    >>> significant(0.75412), significant(3594.2), significant(-10613.0), significant(7.0)
    ('0.754', '3594', '-10613', '7')
    >>> significant(0.000123), significant(2.5e7)
    ('0.000123', '2.5e+07')
    """
    if 10 ** (digits - 1) <= abs(value) < 1e6:
        return f"{value:.0f}"
    return f"{value:.{digits}g}"


def interval_text(value, low, high, *, fmt: str = ".3f") -> str:
    """``value [low, high]``, ``value (no interval)`` or ``n/a``; ``fmt`` is a format
    specification, or ``sig`` for :func:`significant`.

    Examples
    --------
    >>> interval_text(0.75412, 0.7311, 0.7766)
    '0.754 [0.731, 0.777]'
    >>> interval_text(7.04, None, "", fmt="sig"), interval_text(float("nan"), 0, 1)
    ('7.04 (no interval)', 'n/a')
    """
    v, lo, hi = _f(value), _f(low), _f(high)

    def show(x):
        return significant(x) if fmt == "sig" else format(x, fmt)

    if not math.isfinite(v):
        return "n/a"
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return f"{show(v)} (no interval)"
    return f"{show(v)} [{show(lo)}, {show(hi)}]"
