"""Variance fields on a logarithmic scale, as Fig. 1, Fig. 3 and the cross-renderer figure
draw them: the colour map and its limits, log-spaced histogram edges, and the Pearson
coefficient printed in the figures (Eq. 3, paper Sec. 2.3), computed here in float64 with
numpy, independently of the measurement modules.
"""

from __future__ import annotations

import math

import numpy as np

MASK_COLOUR = "#808080"
UNDER_COLOUR = "#000000"
VARIANCE_CMAP = "magma"
ROBUST_PERCENTILES = (1.0, 99.5)
"""Percentiles of the positive values that set the shared colour limits of Fig. 1 (a)-(c)."""


def _pearson(a, b) -> float:
    """Pearson coefficient of two 1-D samples in float64; NaN if undefined.

    Undefined means fewer than two samples or a zero-variance sample.
    """
    a = np.asarray(a, dtype=np.float64).ravel()
    b = np.asarray(b, dtype=np.float64).ravel()
    if a.size < 2:
        return math.nan
    da = a - a.mean()
    db = b - b.mean()
    denom = math.sqrt(float(np.dot(da, da))) * math.sqrt(float(np.dot(db, db)))
    if not denom > 0 or not math.isfinite(denom):
        return math.nan
    return float(np.clip(np.dot(da, db) / denom, -1.0, 1.0))


def _fmt_rho(rho: float) -> str:
    """:math:`\\rho` to 4 decimals, as the figures print it; ``n/a`` when not finite."""
    return "n/a" if not math.isfinite(rho) else f"{rho:.4f}"


def _log_limits(values: np.ndarray, percentiles=None) -> tuple[float, float]:
    """Log-axis limits from the positive finite ``values`` (optionally robust percentiles).

    Falls back to ``(0.1, 10)`` with no positive values and widens a zero-width range by a
    factor of ten on each side.
    """
    v = values[np.isfinite(values) & (values > 0)]
    if v.size == 0:
        return 0.1, 10.0
    if percentiles is None:
        lo, hi = float(v.min()), float(v.max())
    else:
        lo, hi = (float(p) for p in np.percentile(v, percentiles))
    if not hi > lo:
        lo, hi = lo / 10.0, hi * 10.0
    return lo, hi


def _log_edges(lo: float, hi: float, bins: int) -> np.ndarray:
    edges = np.geomspace(lo, hi, bins + 1)
    edges[0], edges[-1] = lo, hi
    return edges
