"""Fig. 3 of the paper: the scatter of :math:`(\\sigma_L^2, \\hat\\sigma_{R\\to L}^2)` over
the valid set, glass against non-glass, with each group's Pearson :math:`\\rho` (Eq. 3).

Pure, as every figure: arrays in, a matplotlib figure on the Agg backend out; the caller
saves it.
"""

from __future__ import annotations

import numpy as np

from .fields import _fmt_rho, _log_limits, _pearson
from .layout import wrap_to_width
from .plotting import _as_2d, _check_shapes, _pyplot

NON_GLASS_COLOUR = "#8c8c8c"
GLASS_COLOUR = "#d62728"
"""Colours of the non-glass and the glass points."""


def _subsample(n: int, max_points: int, rng: np.random.Generator) -> np.ndarray:
    if n <= max_points:
        return np.arange(n)
    return np.sort(rng.choice(n, size=max_points, replace=False))


def material_scatter_figure(
    sigma_left,
    warped,
    omega,
    glass,
    *,
    title: str = "",
    max_points: int = 50000,
    seed: int = 0,
):
    """Fig. 3: scatter of :math:`(\\sigma_L^2, \\hat\\sigma_{R\\to L}^2)` over Ω by material.

    Non-glass pixels of :math:`\\Omega` are grey, glass pixels red and drawn on top, on
    log-log axes with the line :math:`y = x` (paper Fig. 3, Sec. 3.5). Each group's legend
    entry gives its Pearson :math:`\\rho` (Eq. 3, float64) over all its finite
    :math:`\\Omega` pixels, zeros included, and its pixel count.

    Only pixels with both values positive can be placed on log axes; of those, each group is
    subsampled without replacement to at most ``max_points`` points, deterministically: one
    :func:`numpy.random.default_rng` ``(seed)`` draws the non-glass subsample, then the
    glass one. The kept points stay in raster order.

    Parameters
    ----------
    sigma_left, warped : numpy.ndarray or xarray.DataArray, shape (H, W)
        The left variance field and the right one warped into left coordinates.
    omega : array_like of bool, shape (H, W)
        The valid set :math:`\\Omega`.
    glass : array_like of bool, shape (H, W)
        Left-view glass mask (the ground truth's ``glass``).
    title : str, keyword-only
        Axes title.
    max_points : int, keyword-only
        Most points drawn per group.
    seed : int, keyword-only
        Seed of the subsampling generator.

    Returns
    -------
    matplotlib.figure.Figure
        One axes; its collections are the non-glass then the glass scatter.

    Raises
    ------
    ValueError
        If the inputs are not 2-D arrays of one shape or ``max_points < 1``.
    """
    plt = _pyplot()
    if max_points < 1:
        raise ValueError(f"max_points must be >= 1, got {max_points}")
    sl = _as_2d(sigma_left, "sigma_left")
    sw = _as_2d(warped, "warped")
    om = _as_2d(omega, "omega", dtype=bool)
    gl = _as_2d(glass, "glass", dtype=bool)
    _check_shapes(sigma_left=sl, warped=sw, omega=om, glass=gl)

    finite = om & np.isfinite(sl) & np.isfinite(sw)
    positive = finite & (sl > 0) & (sw > 0)
    rng = np.random.default_rng(seed)
    fig, ax = plt.subplots(figsize=(5.0, 5.0), constrained_layout=True)
    groups = (
        ("non-glass", om & ~gl, NON_GLASS_COLOUR, 2),
        ("glass", om & gl, GLASS_COLOUR, 3),
    )
    for name, region, colour, zorder in groups:
        n_region = int(region.sum())
        pos = region & positive
        x, y = sl[pos], sw[pos]
        keep = _subsample(x.size, max_points, rng)
        if n_region == 0:
            label = f"{name}: no pixels"
        else:
            rho = _pearson(sl[region & finite], sw[region & finite])
            label = f"{name}: $\\rho = {_fmt_rho(rho)}$ ($n = {n_region}$"
            label += f", {keep.size} shown)" if keep.size < n_region else ")"
        ax.scatter(
            x[keep],
            y[keep],
            s=2,
            color=colour,
            alpha=0.5 if name == "glass" else 0.35,
            linewidths=0,
            zorder=zorder,
            rasterized=True,
            label=label,
        )
    lo, hi = _log_limits(np.concatenate([sl[positive], sw[positive]]))
    pad = (hi / lo) ** 0.03
    lo, hi = lo / pad, hi * pad
    ax.plot([lo, hi], [lo, hi], color="black", linewidth=1.0, zorder=4, label="$y = x$")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_aspect("equal")
    ax.set_xlabel(r"$\sigma_L^2$")
    ax.set_ylabel(r"$\hat\sigma_{R\to L}^2$")
    legend = ax.legend(loc="upper left", fontsize="small", markerscale=4)
    for handle in legend.legend_handles:
        if hasattr(handle, "set_alpha"):
            handle.set_alpha(1.0)
    if title:
        ax.set_title(wrap_to_width(title, 0.8 * fig.get_figwidth(), fontsize=_title_size()))
    return fig


def _title_size() -> float:
    """Font size of an axes title, in points."""
    import matplotlib
    from matplotlib.font_manager import FontProperties

    return FontProperties(size=matplotlib.rcParams["axes.titlesize"]).get_size_in_points()
