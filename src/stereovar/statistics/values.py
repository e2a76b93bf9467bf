"""Reading table cells as numbers: a missing or unreadable cell is NaN.

Rows read back from CSV tables carry numbers as strings, blanks or None; the rules that
decide on them treat every such cell as not finite.
"""

from __future__ import annotations

import math


def as_float(value) -> float:
    """``value`` as a float, NaN when it is none.

    Examples
    --------
    >>> as_float("0.25"), as_float(None), as_float("")
    (0.25, nan, nan)
    """
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def all_finite(*values) -> bool:
    """Whether every value reads as a finite number.

    Examples
    --------
    >>> all_finite(0.1, "2"), all_finite(0.1, None), all_finite("inf")
    (True, False, False)
    """
    return all(math.isfinite(as_float(v)) for v in values)
