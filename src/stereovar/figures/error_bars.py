"""Error bars of correlation rows: each row's 95% interval and its kind (the spatial block
bootstrap's, or the Fisher-z interval where the row has none), the bars' extents, and the
legend note that names the intervals drawn.
"""

from __future__ import annotations

import math

import numpy as np

from .plotting import _finite

BOOTSTRAP = "bootstrap"
FISHER = "fisher"
"""Kinds of 95% interval a correlation row carries (:func:`_interval`)."""


def _interval(row) -> tuple[float, float, str | None]:
    """A correlation row's 95% interval and its kind.

    The spatial block bootstrap interval (``boot_low``, ``boot_high``) where the row has a
    finite bound of it, else the Fisher-z interval (``fisher_low``, ``fisher_high``, which
    assumes independent pixels); the kind is :data:`BOOTSTRAP`, :data:`FISHER` or ``None``
    when neither has a finite bound.
    """
    low, high = _finite(row.get("boot_low")), _finite(row.get("boot_high"))
    if math.isfinite(low) or math.isfinite(high):
        return low, high, BOOTSTRAP
    low, high = _finite(row.get("fisher_low")), _finite(row.get("fisher_high"))
    if math.isfinite(low) or math.isfinite(high):
        return low, high, FISHER
    return low, high, None


def _bar_extents(centre, low, high) -> np.ndarray:
    """Asymmetric error-bar lengths, shape (2, n), from interval bounds.

    A missing bound gives no bar on its side and a bound on the wrong side of ``centre`` a
    zero-length one.
    """
    centre, low, high = (np.asarray(a, dtype=np.float64) for a in (centre, low, high))
    lower = np.where(np.isfinite(low), np.maximum(centre - low, 0.0), 0.0)
    upper = np.where(np.isfinite(high), np.maximum(high - centre, 0.0), 0.0)
    return np.vstack([lower, upper])


def _interval_note(kinds) -> str:
    """Legend title naming the intervals drawn as error bars."""
    kinds = set(kinds)
    lines = []
    if BOOTSTRAP in kinds:
        lines.append("bars: spatial block bootstrap 95%")
    if FISHER in kinds:
        lines.append("hollow: Fisher-z 95% (no bootstrap)")
    return "\n".join(lines)
