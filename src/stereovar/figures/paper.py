"""Paper figures: the teaser (Fig. 1), rho versus SPP (Fig. 2) and the material scatter (Fig. 3).

Every function here is pure: it takes arrays or rows, builds a matplotlib figure on the Agg
backend and returns it; the caller saves it. The Pearson coefficients printed in the figures
(Eq. 3, paper Sec. 2.3) are computed here in float64 with numpy, independently of the
measurement modules.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..statistics.regions import REGIONS
from .layout import wrap_to_width

"""Material regions of Fig. 2, in plotting order (paper Sec. 3.3 and Sec. 3.5)."""

REGION_LABELS = {"all": "all pixels", "non_glass": "non-glass", "glass": "glass"}
REGION_COLOURS = {"all": "#1f3b73", "non_glass": "#7f7f7f", "glass": "#c44e52"}
NON_GLASS_COLOUR = "#8c8c8c"
GLASS_COLOUR = "#d62728"
MASK_COLOUR = "#808080"
UNDER_COLOUR = "#000000"
VARIANCE_CMAP = "magma"
ROBUST_PERCENTILES = (1.0, 99.5)
"""Percentiles of the positive values that set the shared colour limits of Fig. 1 (a)-(c)."""


def _pyplot():
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
    shapes = {k: v.shape for k, v in arrays.items()}
    if len(set(shapes.values())) > 1:
        raise ValueError(f"shape mismatch: {shapes}")


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


def _finite(value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return math.nan
    return v if math.isfinite(v) else math.nan


def _relative_variation(values) -> float:
    v = np.asarray([x for x in values if math.isfinite(x)], dtype=np.float64)
    if v.size == 0:
        return math.nan
    mean = float(v.mean())
    if mean == 0:
        return math.nan
    return float((v.max() - v.min()) / abs(mean))


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


STATISTIC_LABELS = {
    "warp": "Pearson (Eq. 3)",
    "spearman": "Spearman",
    "log": r"Pearson of $\ln\sigma^2$",
    "trimmed": "trimmed Pearson",
}
"""Legend names of the statistics of :mod:`stereovar.statistics.registry`."""

SECONDARY_STYLES = (("--", "s"), (":", "^"), ("-.", "v"))
"""Line style and marker of the first, second, ... secondary statistic of Fig. 2."""

SECONDARY_SHIFT = 0.07
"""Horizontal shift of the secondary statistics in Fig. 2, in octaves of SPP (alternating
right and left, growing), so their bars stand beside the primary's."""


def _statistic_label(method: str) -> str:
    return STATISTIC_LABELS.get(method, method.replace("_", "-"))


def rho_vs_spp_figure(
    rows, *, title: str = "", primary: str = "warp", secondary=("spearman", "log")
):
    """Fig. 2: cross-view correlation :math:`\\rho` against samples per pixel, per region.

    One line with markers per material region (all pixels, non-glass, glass; paper Fig. 2,
    Sec. 3.3) for the ``primary`` statistic (Pearson, Eq. 3), on a :math:`\\log_2` SPP axis
    with a tick at every given SPP. Its legend (:meth:`~matplotlib.axes.Axes.get_legend`)
    has one entry per region with the region's relative variation
    :math:`(\\max\\rho - \\min\\rho) / \\overline{\\rho}` over its plotted points, the
    figure the paper quotes (0.12 % for non-glass), and a title naming the intervals drawn.

    Error bars are the spatial block bootstrap's 95% interval (``boot_low``,
    ``boot_high``). A row with no finite bootstrap bound falls back to its Fisher-z interval
    (``fisher_low``, ``fisher_high``), which assumes independent pixels and is far too
    narrow for spatially correlated fields; such points get a hollow marker and the legend
    title says so. A missing bound gives no bar on that side, a bound on the wrong side of
    ``rho`` a zero-length one.

    The ``secondary`` statistics (:mod:`stereovar.statistics.registry`; by default the
    robust ones, Spearman and Pearson of :math:`\\ln\\sigma^2`) are drawn beside it in the
    region's colour, thinner, with their own line style and marker (named by a second
    legend) and their own bars, shifted by :data:`SECONDARY_SHIFT` octaves so the bars do
    not overlap.

    A row whose ``rho`` or ``spp`` is missing or not finite is omitted (its SPP still gets
    a tick when finite); rows of any other statistic are ignored.

    Parameters
    ----------
    rows : list of dict
        Keys ``spp`` (int), ``region`` (one of ``"all"``, ``"non_glass"``, ``"glass"``),
        ``rho``, ``boot_low``, ``boot_high`` and/or ``fisher_low``, ``fisher_high`` (float,
        NaN allowed) and optionally ``method`` (rows without one are ``primary``).
    title : str, keyword-only
        Axes title.
    primary : str, keyword-only
        The statistic drawn with markers and a solid line per region.
    secondary : sequence of str, keyword-only
        Statistics drawn beside it.

    Returns
    -------
    matplotlib.figure.Figure
        One axes. Its ``containers`` hold one
        :class:`matplotlib.container.ErrorbarContainer` per region with primary data, in
        :data:`REGIONS` order, labelled ``"<region label> (rel. var. ...)"``, then one per
        (secondary statistic, region) with data, labelled ``"<region label>, <method>"``.

    Raises
    ------
    ValueError
        If a row names an unknown region.
    """
    from matplotlib.lines import Line2D
    from matplotlib.ticker import NullLocator

    plt = _pyplot()
    secondary = tuple(m for m in secondary if m != primary)
    points: dict[tuple[str, str], list[tuple[float, float, float, float, str | None]]] = {}
    all_spp: set[float] = set()
    for row in rows:
        region = row["region"]
        if region not in REGIONS:
            raise ValueError(f"unknown region {region!r}; expected one of {REGIONS}")
        spp = _finite(row.get("spp"))
        if not (math.isfinite(spp) and spp > 0):
            continue
        all_spp.add(spp)
        rho = _finite(row.get("rho"))
        method = row.get("method", primary)
        if not math.isfinite(rho) or (method != primary and method not in secondary):
            continue
        points.setdefault((method, region), []).append((spp, rho, *_interval(row)))

    fig, ax = plt.subplots(figsize=(8.0, 4.2), constrained_layout=True)
    kinds: set[str | None] = set()
    region_handles, region_labels = [], []
    for method in (primary, *secondary):
        if method == primary:
            style = {"linestyle": "-", "marker": "o", "markersize": 4, "capsize": 3}
            shift = 1.0
        else:
            i = secondary.index(method)
            linestyle, marker = SECONDARY_STYLES[i % len(SECONDARY_STYLES)]
            style = {
                "linestyle": linestyle,
                "marker": marker,
                "markersize": 3,
                "capsize": 2,
                "linewidth": 1.0,
                "elinewidth": 0.8,
                "alpha": 0.75,
            }
            shift = 2.0 ** (SECONDARY_SHIFT * (i // 2 + 1) * (1 if i % 2 == 0 else -1))
        for region in REGIONS:
            pts = sorted(points.get((method, region), []), key=lambda p: p[0])
            if not pts:
                continue
            spp = np.array([p[0] for p in pts]) * shift
            rho = np.array([p[1] for p in pts])
            low = np.array([p[2] for p in pts])
            high = np.array([p[3] for p in pts])
            kind = [p[4] for p in pts]
            kinds.update(kind)
            colour = REGION_COLOURS[region]
            if method == primary:
                rel = _relative_variation(rho)
                rel_text = "n/a" if not math.isfinite(rel) else f"{100 * rel:.2f}%"
                label = f"{REGION_LABELS[region]} (rel. var. {rel_text})"
            else:
                label = f"{REGION_LABELS[region]}, {method}"
            container = ax.errorbar(
                spp, rho, yerr=_bar_extents(rho, low, high), color=colour, label=label, **style
            )
            fallback = np.array([k == FISHER for k in kind])
            if fallback.any():
                ax.plot(
                    spp[fallback],
                    rho[fallback],
                    linestyle="none",
                    marker=style["marker"],
                    markersize=style["markersize"] + 1,
                    markerfacecolor="white",
                    markeredgecolor=colour,
                    zorder=container.lines[0].get_zorder() + 0.1,
                    label="_Fisher-z fallback",
                )
            if method == primary:
                region_handles.append(container)
                region_labels.append(label)
    ax.set_xscale("log", base=2)
    ticks = sorted(all_spp)
    if ticks:
        ax.set_xticks(ticks, labels=[f"{t:g}" for t in ticks])
        ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xlabel("samples per pixel (SPP)")
    ax.set_ylabel(r"$\rho$")
    drawn_secondary = [m for m in secondary if any(k[0] == m for k in points)]
    if drawn_secondary:
        proxies = [Line2D([], [], color="black", linestyle="-", marker="o", markersize=4)]
        proxies += [
            Line2D([], [], color="black", linestyle=ls, marker=mk, markersize=3, linewidth=1.0)
            for ls, mk in (
                SECONDARY_STYLES[secondary.index(m) % len(SECONDARY_STYLES)]
                for m in drawn_secondary
            )
        ]
        statistics_legend = ax.legend(
            proxies,
            [_statistic_label(m) for m in (primary, *drawn_secondary)],
            title="statistic",
            fontsize="small",
            title_fontsize="small",
            loc="lower left",
            bbox_to_anchor=(1.02, 0.0),
            borderaxespad=0.0,
        )
        ax.add_artist(statistics_legend)
    if points:
        ax.legend(
            region_handles,
            region_labels,
            title=_interval_note(kinds) or None,
            fontsize="small",
            title_fontsize="small",
            loc="upper left",
            bbox_to_anchor=(1.02, 1.0),
            borderaxespad=0.0,
        )
    else:
        ax.text(0.5, 0.5, "no data", ha="center", va="center", transform=ax.transAxes)
    ax.grid(True, alpha=0.3)
    if title:
        ax.set_title(title)
    return fig


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


def symlog_ticks(lo: float, hi: float, linthresh: float, *, per_side: int = 3) -> list[float]:
    """Major ticks of a symmetric-log axis from ``lo`` to ``hi``: 0 and the powers of ten
    beyond ``linthresh`` on each side, every k-th decade counted down from the largest one
    on either side, so that at most ``per_side`` remain per side; both sides share them.

    Powers of ten inside the linear part :math:`|m| < s` sit close to 0, where their labels
    would run into the label of 0; they are left out.

    Examples
    --------
    >>> symlog_ticks(-100.0, 10.0, 0.003)
    [-100.0, -1.0, -0.01, 0.0, 0.01, 1.0]
    >>> symlog_ticks(-0.5, 0.5, 0.1)
    [-0.1, 0.0, 0.1]
    >>> symlog_ticks(0.5, 2.0, 1.0)
    [1.0]
    """
    ticks = [0.0] if lo <= 0.0 <= hi else []
    first = math.ceil(math.log10(linthresh))
    reach = {-1.0: -lo, 1.0: hi}
    top = max((math.floor(math.log10(r)) for r in reach.values() if r > linthresh), default=None)
    if top is None:
        return ticks
    stride = max(math.ceil((top - first + 1) / per_side), 1)
    for sign, r in reach.items():
        ticks += [sign * 10.0**e for e in range(top, first - 1, -stride) if r >= 10.0**e]
    return sorted(ticks)


MARGIN_COSTS = {
    "residual_sad": "residual SAD $C_\\epsilon$",
    "variance_cost": "variance cost $C_\\sigma$",
}
CONDITION_COLOURS = {"normal": "#1f3b73", "decorrelated": "#dd8452"}


def margin_distribution_figure(samples, *, title: str = "", bins: int = 60):
    """GT-margin distributions of the intervention, normal against decorrelated (Sec. 3.4).

    .. math:: m(x) = \\min_{d \\ne d_{GT}} C(x, d) - C(x, d_{GT})

    One panel per cost (rows: :math:`C_\\epsilon`, :math:`C_\\sigma`) and region (columns:
    non-glass, glass) overlays the histograms of the normal and the decorrelated margins
    (share of the margins per bin) on shared bins, with a dashed line at :math:`m = 0`
    (right of it the ground truth wins). Margins are heavy-tailed, so the x axis is
    symmetric-log, linear within :math:`\\pm s` with :math:`s` the median :math:`|m|` of the
    panel's pooled margins, and the bins are uniform in :math:`\\operatorname{asinh}(m / s)`
    from the smallest to the largest margin. Each legend label gives the median,
    :math:`\\Pr[m > 0]` and the number of margins.

    Parameters
    ----------
    samples : iterable of mapping
        Margin rows (``cost``, ``region``, ``condition``, ``margin``), e.g. the
        ``results/intervention/margins/<scene>.csv`` files pooled over scenes.
    title : str, keyword-only
        Figure title.
    bins : int, keyword-only
        Number of histogram bins.

    Returns
    -------
    matplotlib.figure.Figure
        A 2 x 2 grid; axes in row-major order (cost, region).
    """
    from ..intervention.metrics import CONDITIONS
    from ..intervention.metrics import REGIONS as INTERVENTION_REGIONS

    plt = _pyplot()
    if bins < 1:
        raise ValueError(f"bins must be >= 1, got {bins}")
    groups: dict = {}
    for s in samples:
        value = _finite(s["margin"])
        if math.isfinite(value):
            groups.setdefault((s["cost"], s["region"], s["condition"]), []).append(value)
    fig, axes = plt.subplots(
        len(MARGIN_COSTS),
        len(INTERVENTION_REGIONS),
        figsize=(10.0, 7.5),
        constrained_layout=True,
        squeeze=False,
    )
    for i, (cost, cost_label) in enumerate(MARGIN_COSTS.items()):
        for j, region in enumerate(INTERVENTION_REGIONS):
            ax = axes[i, j]
            data = {c: np.asarray(groups.get((cost, region, c), [])) for c in CONDITIONS}
            pooled = np.concatenate(list(data.values()))
            ax.set_title(f"{cost_label}, {REGION_LABELS[region]}", fontsize="medium")
            if pooled.size == 0:
                ax.text(0.5, 0.5, "no scored pixels", ha="center", va="center",
                        transform=ax.transAxes)  # fmt: skip
                continue
            scale = float(np.median(np.abs(pooled)))
            if not scale > 0:
                scale = float(np.max(np.abs(pooled))) or 1.0
            lo, hi = np.arcsinh(np.array([pooled.min(), pooled.max()]) / scale)
            if hi > lo:
                edges = scale * np.sinh(np.linspace(lo, hi, bins + 1))
                edges[[0, -1]] = pooled.min(), pooled.max()  # exact ends: sinh(asinh(v)) rounds
            else:  # one distinct value
                edges = pooled[0] + scale * np.linspace(-0.5, 0.5, bins + 1)
            for condition, values in data.items():
                if not values.size:
                    continue
                label = (
                    f"{condition}: median {np.median(values):.3g}, "
                    f"P(m>0) {np.mean(values > 0):.1%}, n={values.size}"
                )
                ax.hist(
                    values,
                    bins=edges,
                    weights=np.full(values.size, 1.0 / values.size),
                    histtype="step",
                    linewidth=1.6,
                    color=CONDITION_COLOURS[condition],
                    label=label,
                )
            ax.set_ylim(0.0, ax.get_ylim()[1] * 1.35)  # headroom for the legend
            ax.axvline(0.0, color="black", linestyle="--", linewidth=0.8)
            ax.set_xscale("symlog", linthresh=scale)
            ax.set_xticks(symlog_ticks(float(edges[0]), float(edges[-1]), scale))
            ax.set_xlabel(f"GT margin m (symlog, linear within ±{scale:.2g})")
            ax.set_ylabel("share of margins per bin")
            ax.tick_params(axis="x", labelsize="small")
            ax.legend(fontsize="x-small", loc="best", framealpha=0.85)
            ax.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    return fig
