"""What the figure modules share: pyplot on the Agg backend, the material regions with their
labels and colours, the statistics' legend names, and a number or a 2-D field as the figures
take them.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..statistics.regions import REGIONS

"""Material regions of Fig. 2, in plotting order (paper Sec. 3.3 and Sec. 3.5)."""

__all__ = ["REGIONS", "REGION_COLOURS", "REGION_LABELS", "STATISTIC_LABELS"]

REGION_LABELS = {"all": "all pixels", "non_glass": "non-glass", "glass": "glass"}
REGION_COLOURS = {"all": "#1f3b73", "non_glass": "#7f7f7f", "glass": "#c44e52"}

STATISTIC_LABELS = {
    "warp": "Pearson (Eq. 3)",
    "spearman": "Spearman",
    "log": r"Pearson of $\ln\sigma^2$",
    "trimmed": "trimmed Pearson",
}
"""Legend names of the statistics of :mod:`stereovar.statistics.registry`."""


def _pyplot():
    """:mod:`matplotlib.pyplot` on the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _as_2d(a, name: str, dtype=np.float64) -> np.ndarray:
    """A 2-D numpy array on (y, x) from a numpy array or an xarray DataArray."""
    if isinstance(a, xr.DataArray):
        if set(a.dims) == {"y", "x"}:
            a = a.transpose("y", "x")
        a = a.values
    arr = np.asarray(a, dtype=dtype)
    if arr.ndim != 2:
        raise ValueError(f"{name} must be 2-D on (y, x), got shape {arr.shape}")
    return arr


def _check_shapes(**arrays: np.ndarray) -> None:
    """Raise :class:`ValueError` naming each array's shape unless ``arrays`` share one."""
    shapes = {k: v.shape for k, v in arrays.items()}
    if len(set(shapes.values())) > 1:
        raise ValueError(f"shape mismatch: {shapes}")


def _finite(value) -> float:
    """``value`` as a float; NaN where it is missing, not a number or not finite."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return math.nan
    return v if math.isfinite(v) else math.nan


def _statistic_label(method: str) -> str:
    """A statistic's legend name (:data:`STATISTIC_LABELS`, else its name hyphenated)."""
    return STATISTIC_LABELS.get(method, method.replace("_", "-"))
