"""Fig. 1 of the paper, the teaser: both views' variance fields, the right one warped into
left coordinates, and their joint histogram over the valid set with Pearson's
:math:`\\rho` (Eq. 3).

Pure, as every figure: arrays in, a matplotlib figure on the Agg backend out; the caller
saves it.
"""

from __future__ import annotations

import numpy as np

from .fields import (
    MASK_COLOUR,
    ROBUST_PERCENTILES,
    UNDER_COLOUR,
    VARIANCE_CMAP,
    _fmt_rho,
    _log_edges,
    _log_limits,
    _pearson,
)
from .plotting import _as_2d, _check_shapes, _pyplot


def teaser_figure(sigma_left, sigma_right, warped, omega, *, title: str = "", bins: int = 200):
    """Fig. 1 (teaser): both variance fields, the warped right field and their joint histogram.

    Panels (paper Fig. 1, Sec. 2.1-2.3):

    (a) :math:`\\sigma_L^2`, (b) :math:`\\sigma_R^2` (Eq. 1);
    (c) :math:`\\hat\\sigma_{R\\to L}^2` (Eq. 2), grey outside the valid set :math:`\\Omega`;
    (d) the joint 2-D histogram of :math:`(\\sigma_L^2, \\hat\\sigma_{R\\to L}^2)` over
    :math:`\\Omega` with the line :math:`y = x` in red, and the Pearson :math:`\\rho` over
    :math:`\\Omega` (Eq. 3) in its title.

    Panels (a)-(c) share one logarithmic colour scale (:class:`matplotlib.colors.LogNorm`)
    whose limits are the 1st and 99.5th percentiles of the positive finite values of the three
    displayed fields, and one colour bar. Zero or negative variances are drawn in the colour
    map's "under" colour (black), as are values below the lower limit; non-finite values and
    pixels outside :math:`\\Omega` in (c) are drawn in the "bad" colour (grey).

    Panel (d) bins the :math:`\\Omega` pixels where both values are positive and finite into
    ``bins`` log-spaced bins per axis over the same range on both axes, with a logarithmic
    count scale; the Pearson :math:`\\rho` in its title is over all finite :math:`\\Omega`
    pixels, zeros included, as in Eq. 3.

    Parameters
    ----------
    sigma_left, sigma_right : numpy.ndarray or xarray.DataArray, shape (H, W)
        Per-pixel variance fields of the left and right view (DataArrays on ``y``, ``x``).
    warped : numpy.ndarray or xarray.DataArray, shape (H, W)
        The right field warped into left coordinates
        (:func:`stereovar.statistics.warp.warp_right_to_left`).
    omega : array_like of bool, shape (H, W)
        The valid set :math:`\\Omega` of the warp.
    title : str, keyword-only
        Figure title.
    bins : int, keyword-only
        Number of log-spaced histogram bins per axis of panel (d).

    Returns
    -------
    matplotlib.figure.Figure
        Axes in order (a), (b), (c), (d), then the colour bars.

    Raises
    ------
    ValueError
        If the inputs are not 2-D arrays of one shape or ``bins < 1``.
    """
    from matplotlib.colors import LogNorm

    plt = _pyplot()
    if bins < 1:
        raise ValueError(f"bins must be >= 1, got {bins}")
    sl = _as_2d(sigma_left, "sigma_left")
    sr = _as_2d(sigma_right, "sigma_right")
    sw = _as_2d(warped, "warped")
    om = _as_2d(omega, "omega", dtype=bool)
    _check_shapes(sigma_left=sl, sigma_right=sr, warped=sw, omega=om)
    height, width = sl.shape

    shown = np.concatenate([sl.ravel(), sr.ravel(), sw[om]])
    vmin, vmax = _log_limits(shown, ROBUST_PERCENTILES)
    under = vmin * 1e-3
    cmap = plt.get_cmap(VARIANCE_CMAP).with_extremes(bad=MASK_COLOUR, under=UNDER_COLOUR)

    def display(field, mask=None):
        data = np.where(np.isfinite(field) & (field <= 0), under, field)
        invalid = ~np.isfinite(field)
        if mask is not None:
            invalid |= ~mask
        return np.ma.masked_array(data, mask=invalid)

    aspect = height / width if width else 1.0
    fig, axes = plt.subplots(
        1,
        4,
        figsize=(17, max(3.2, 4.0 * aspect) + 1.0),
        gridspec_kw={"width_ratios": [1, 1, 1, 1.15 * max(aspect, 0.5)]},
        constrained_layout=True,
    )
    panels = (
        (sl, None, r"(a) $\sigma_L^2$"),
        (sr, None, r"(b) $\sigma_R^2$"),
        (sw, om, r"(c) $\hat\sigma_{R\to L}^2$ (grey: not seen by both views)"),
    )
    image = None
    for ax, (field, mask, name) in zip(axes[:3], panels, strict=True):
        image = ax.imshow(
            display(field, mask),
            cmap=cmap,
            norm=LogNorm(vmin=vmin, vmax=vmax),
            interpolation="nearest",
        )
        ax.set_title(name)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.colorbar(image, ax=list(axes[:3]), shrink=0.85, extend="both", label="variance")

    ax = axes[3]
    x, y = sl[om], sw[om]
    finite = np.isfinite(x) & np.isfinite(y)
    rho = _pearson(x[finite], y[finite])
    pos = finite & (x > 0) & (y > 0)
    n_omega, n_pos = int(om.sum()), int(pos.sum())
    ax.set_xlabel(r"$\sigma_L^2$")
    ax.set_ylabel(r"$\hat\sigma_{R\to L}^2$")
    if n_omega == 0 or n_pos == 0:
        message = "no valid pixels" if n_omega == 0 else "no positive pixel pairs"
        ax.text(0.5, 0.5, message, ha="center", va="center", transform=ax.transAxes)
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(f"(d) joint, pixels both views see ($n = {n_omega}$)")
    else:
        lo, hi = _log_limits(np.concatenate([x[pos], y[pos]]))
        edges = _log_edges(lo, hi, bins)
        counts, _, _ = np.histogram2d(x[pos], y[pos], bins=(edges, edges))
        mesh = ax.pcolormesh(
            edges,
            edges,
            np.ma.masked_equal(counts.T, 0),
            cmap="viridis",
            norm=LogNorm(vmin=1, vmax=max(float(counts.max()), 1.0)),
            rasterized=True,
        )
        ax.plot([lo, hi], [lo, hi], color="red", linewidth=1.0, label="$y = x$")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(lo, hi)
        ax.set_ylim(lo, hi)
        ax.set_aspect("equal")
        ax.legend(loc="upper left", fontsize="small")
        fig.colorbar(mesh, ax=ax, shrink=0.85, label="pixels per bin")
        ax.set_title(
            f"(d) joint, pixels both views see\n$\\rho = {_fmt_rho(rho)}$ ($n = {n_omega}$)"
        )
    if title:
        fig.suptitle(title)
    return fig
