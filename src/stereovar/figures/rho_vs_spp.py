"""Fig. 2 of the paper: the cross-view correlation :math:`\\rho` against samples per pixel,
per material region, with its 95% intervals and the robust statistics beside Pearson's.

Pure, as every figure: rows in, a matplotlib figure on the Agg backend out; the caller
saves it.
"""

from __future__ import annotations

import math

import numpy as np

from .error_bars import FISHER, _bar_extents, _interval, _interval_note
from .plotting import (
    REGION_COLOURS,
    REGION_LABELS,
    REGIONS,
    _finite,
    _pyplot,
    _statistic_label,
)


def _relative_variation(values) -> float:
    v = np.asarray([x for x in values if math.isfinite(x)], dtype=np.float64)
    if v.size == 0:
        return math.nan
    mean = float(v.mean())
    if mean == 0:
        return math.nan
    return float((v.max() - v.min()) / abs(mean))


SECONDARY_STYLES = (("--", "s"), (":", "^"), ("-.", "v"))
"""Line style and marker of the first, second, ... secondary statistic of Fig. 2."""

SECONDARY_SHIFT = 0.07
"""Horizontal shift of the secondary statistics in Fig. 2, in octaves of SPP (alternating
right and left, growing), so their bars stand beside the primary's."""


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
