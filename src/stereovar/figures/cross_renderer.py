"""The cross-renderer figure: one scene's variance fields from every renderer, side by side."""

from __future__ import annotations

import math

import numpy as np
from matplotlib.colors import LogNorm

from .fields import (
    ROBUST_PERCENTILES,
    UNDER_COLOUR,
    VARIANCE_CMAP,
    _fmt_rho,
    _log_limits,
)
from .plotting import _as_2d, _pyplot


def cross_renderer_figure(fields: dict, *, rho: dict | None = None, title: str = ""):
    """Left and right :math:`\\sigma^2` fields (Eq. 1) of one scene, a row per renderer, on
    one shared logarithmic colour scale (robust percentiles :data:`ROBUST_PERCENTILES` of
    every positive value), with each renderer's warped :math:`\\rho` and interval.

    Parameters
    ----------
    fields : dict of str to (array_like, array_like)
        Renderer to its (left, right) luminance variance fields, each (H, W).
    rho : dict of str to (float, float, float), optional
        Renderer to its warped rho and bootstrap interval, shown in the row label.
    title : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot()
    arrays = {
        r: (_as_2d(left, f"{r} left"), _as_2d(right, f"{r} right"))
        for r, (left, right) in fields.items()
    }
    every = np.concatenate([a.ravel() for pair in arrays.values() for a in pair])
    lo, hi = _log_limits(every, ROBUST_PERCENTILES)
    cmap = plt.get_cmap(VARIANCE_CMAP).with_extremes(under=UNDER_COLOUR, bad=UNDER_COLOUR)
    n = len(arrays)
    height, width = next(iter(arrays.values()))[0].shape
    fig, axes = plt.subplots(
        n, 2, figsize=(8.0, 0.6 + 4.0 * n * height / width), squeeze=False, layout="constrained"
    )
    image = None
    for k, (renderer, pair) in enumerate(arrays.items()):
        label = renderer
        if rho and renderer in rho:
            value, low, high = rho[renderer]
            label += f"\nrho {_fmt_rho(value)}"
            if math.isfinite(low) and math.isfinite(high):
                label += f" [{low:.3f}, {high:.3f}]"
        for j, (view, field) in enumerate(zip(("left", "right"), pair, strict=True)):
            ax = axes[k, j]
            shown = np.where(field > 0, field, np.nan)
            image = ax.imshow(shown, cmap=cmap, norm=LogNorm(vmin=lo, vmax=hi))
            ax.set_xticks([])
            ax.set_yticks([])
            if k == 0:
                ax.set_title(f"$\\sigma^2_{{{view[0].upper()}}}$")
            if j == 0:
                ax.set_ylabel(label)
    fig.colorbar(image, ax=axes, shrink=0.8, label="luminance variance (log)")
    if title:
        fig.suptitle(title)
    return fig
