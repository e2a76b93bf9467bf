"""Figures of the uncertainty and the controls: :math:`\\rho` against the number of seeds, and
every statistic and control per scene with its bootstrap interval.

Like :mod:`stereovar.figures.rho_vs_spp` (Fig. 2), every function here is pure: it takes rows
(dicts, as :func:`stereovar.io.tables.read_rows` gives them; numbers may be NaN), builds a
matplotlib figure on the Agg backend and returns it; the caller saves it.
"""

from __future__ import annotations

import math

import numpy as np

from .error_bars import _bar_extents
from .layout import wrap_to_width
from .plotting import (
    REGION_LABELS,
    REGIONS,
    _finite,
    _pyplot,
    _statistic_label,
)

STATISTICS = ("warp", "spearman", "log", "trimmed")
"""The statistics of the dot plot, in this order, above the controls."""

CONTROLS = ("no_warp", "null_shift", "null_flip", "partial", "relative", "sensor", "sensor_sim")
"""The controls of the dot plot, in this order."""

METHOD_STYLES = {"warp": ("#1f3b73", "-", "o"), "log": ("#dd8452", "--", "s")}
"""Colour, line style and marker per statistic in :func:`rho_vs_seeds_figure`; other
statistics get the next colour of ``tab10`` and a dotted line."""

ASYMPTOTE_LABEL = "reliability-corrected asymptote"
"""Legend label (prefix) of the dotted lines at the mean attenuation-corrected rho."""


def _no_data(ax) -> None:
    ax.text(0.5, 0.5, "no data", ha="center", va="center", transform=ax.transAxes)


def _method_style(method: str, k: int) -> tuple:
    if method in METHOD_STYLES:
        return METHOD_STYLES[method]
    import matplotlib

    return matplotlib.colormaps["tab10"]((k + 2) % 10), "-.", "^"


def _seed_legend(fig, axes) -> None:
    """One figure legend below the panels: the curves, then the asymptotes."""
    handles: dict[str, object] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, handle)
    labels = sorted(handles, key=lambda label: label.startswith(ASYMPTOTE_LABEL))
    if labels:
        fig.legend(
            [handles[label] for label in labels],
            labels,
            loc="outside lower center",
            ncols=min(len(labels), 2 if len(axes) == 1 else 4),
            fontsize="small",
        )


SEEDS_AXIS = r"seeds $N'$ per subset (largest: all $N$)"
"""x label of :func:`rho_vs_seeds_figure` for the ``seeds`` estimator."""

HALVES_AXIS = r"half renders $N'$ per estimate (2: both halves, all samples)"
"""x label for the ``moments`` estimator, whose subsets are its two half renders."""


def rho_vs_seeds_figure(
    curve_rows,
    *,
    region_order=REGIONS,
    title: str = "",
    methods=("warp", "log"),
    xlabel: str = SEEDS_AXIS,
    drop_empty: bool = False,
):
    """:math:`\\rho` against the number of seeds :math:`N'` in Eq. 1, per region.

    One panel per region. Per statistic (``warp``, Pearson of Eq. 3, solid; ``log``,
    Pearson of :math:`\\ln\\sigma^2`, dashed), the mean over scenes of :math:`\\rho` from
    disjoint subsets of :math:`N'` seeds (``mean_rho``) against :math:`N'` on a
    :math:`\\log_2` axis with a tick at every :math:`N'`, with error bars of
    :math:`\\pm` the standard deviation over scenes (``std_rho``; none where NaN), and a
    horizontal dotted line in the statistic's colour at the mean over scenes of the
    attenuation-corrected :math:`\\rho / \\sqrt{r_L r_R}` of the full estimate
    (``mean_rho_corrected``, :mod:`stereovar.statistics.reliability`), labelled
    :data:`ASYMPTOTE_LABEL`: the level the curve heads for as the estimator noise
    vanishes. The table repeats that value on every :math:`N'` row; the line takes it from
    the largest :math:`N'` with a finite one.

    Rows with a non-finite or non-positive ``n_prime`` or a non-finite ``mean_rho`` are
    left out; a panel with nothing to draw says "no data", or is left out with
    ``drop_empty`` (an audit without a material mask has no glass and no non-glass pixels;
    with no data at all the first panel stays and says so). Rows of other regions or
    statistics are ignored.

    Parameters
    ----------
    curve_rows : list of dict
        Rows of ``tables/seed_curve.csv``: ``region``, ``method``, ``n_prime``,
        ``mean_rho``, ``std_rho``, ``mean_rho_corrected`` and optionally ``n_scenes``.
    region_order : sequence of str, keyword-only
        The regions, one panel each, left to right.
    title : str, keyword-only
        Figure title.
    methods : sequence of str, keyword-only
        The statistics drawn.
    xlabel : str, keyword-only
        Label of the :math:`N'` axis (:data:`SEEDS_AXIS`, :data:`HALVES_AXIS`).
    drop_empty : bool, keyword-only
        Leave out the panels of regions with nothing to draw.

    Returns
    -------
    matplotlib.figure.Figure
        One axes per region in ``region_order`` (with ``drop_empty``: per region with data).
        Each holds one :class:`~matplotlib.container.ErrorbarContainer` per statistic with
        data, in
        ``methods`` order and labelled by the statistic, and one horizontal line per
        statistic with a finite corrected :math:`\\rho`, labelled
        ``"reliability-corrected asymptote, <statistic>"``. One figure legend below.
    """
    from matplotlib.ticker import NullLocator

    plt = _pyplot()
    region_order = tuple(region_order)
    if drop_empty:
        region_order = _with_data(region_order, {r["region"] for r in curve_rows
                                                 if r["method"] in methods and _seed_point(r)})
    fig, axes = plt.subplots(
        1,
        len(region_order),
        figsize=(max(3.8 * len(region_order), 6.0), 4.0),
        sharey=True,
        constrained_layout=True,
        squeeze=False,
    )
    axes = list(axes[0])
    for ax, region in zip(axes, region_order, strict=True):
        ticks: set[float] = set()
        n_scenes: set[int] = set()
        drawn = False
        for k, method in enumerate(methods):
            selected = [r for r in curve_rows if (r["region"], r["method"]) == (region, method)]
            pts = sorted(
                (
                    _finite(r.get("n_prime")),
                    _finite(r.get("mean_rho")),
                    _finite(r.get("std_rho")),
                )
                for r in selected
                if _finite(r.get("n_prime")) > 0 and math.isfinite(_finite(r.get("mean_rho")))
            )
            colour, linestyle, marker = _method_style(method, k)
            name = _statistic_label(method)
            if pts:
                n, rho, std = (np.array(c, dtype=np.float64) for c in zip(*pts, strict=True))
                ticks.update(n.tolist())
                n_scenes.update(
                    int(v)
                    for v in (_finite(r.get("n_scenes")) for r in selected)
                    if math.isfinite(v)
                )
                ax.errorbar(
                    n,
                    rho,
                    yerr=np.where(np.isfinite(std), std, 0.0),
                    marker=marker,
                    markersize=4,
                    capsize=3,
                    linestyle=linestyle,
                    color=colour,
                    label=name,
                )
                drawn = True
            corrected = sorted(
                (_finite(r.get("n_prime")), _finite(r.get("mean_rho_corrected")))
                for r in selected
                if math.isfinite(_finite(r.get("mean_rho_corrected")))
            )
            if corrected:
                ax.axhline(
                    corrected[-1][1],
                    color=colour,
                    linewidth=1.2,
                    linestyle=":",
                    label=f"{ASYMPTOTE_LABEL}, {name}",
                )
                drawn = True
        ax.set_xscale("log", base=2)
        if ticks:
            ax.set_xticks(sorted(ticks), labels=[f"{t:g}" for t in sorted(ticks)])
            ax.xaxis.set_minor_locator(NullLocator())
        ax.set_xlabel(xlabel)
        heading = REGION_LABELS.get(region, region)
        if n_scenes:
            count = max(n_scenes)
            heading += f" ({count} scene{'s' if count != 1 else ''})"
        ax.set_title(heading)
        ax.grid(True, alpha=0.3)
        if not drawn:
            _no_data(ax)
    axes[0].set_ylabel(r"$\rho$, mean over scenes $\pm$ std")
    _seed_legend(fig, axes)
    if title:
        fig.suptitle(wrap_to_width(title, fig.get_figwidth(), fontsize=_suptitle_size()))
    return fig


def _seed_point(row) -> bool:
    """Whether a seed-curve row draws anything: a point or an asymptote."""
    n, rho = _finite(row.get("n_prime")), _finite(row.get("mean_rho"))
    return (n > 0 and math.isfinite(rho)) or math.isfinite(_finite(row.get("mean_rho_corrected")))


def _with_data(region_order: tuple, drawn: set) -> tuple:
    """The regions of ``region_order`` in ``drawn``; the first region where there is none."""
    kept = tuple(r for r in region_order if r in drawn)
    return kept or region_order[:1]


def _suptitle_size() -> float:
    import matplotlib
    from matplotlib.font_manager import FontProperties

    return FontProperties(size=matplotlib.rcParams["figure.titlesize"]).get_size_in_points()


def _dot_offsets(n: int) -> np.ndarray:
    """Vertical offsets of ``n`` scenes within one method's row (at most 0.6 apart)."""
    if n <= 1:
        return np.zeros(max(n, 0))
    spread = min(0.6, 0.12 * (n - 1))
    return np.linspace(-spread / 2, spread / 2, n)


def statistics_dot_figure(
    rows, *, spp=None, title: str = "", region_order=REGIONS, drop_empty: bool = False
):
    """Every statistic and control per scene: :math:`\\rho` with its 95% intervals.

    One panel per region. One row per method: the statistics (:data:`STATISTICS`), a
    dashed separator, then the controls (:data:`CONTROLS`, tick labels in grey), then any
    other method present, alphabetically. Per scene (one colour each, offset vertically
    within the row) a dot at ``rho``, a thin bar with caps over its spatial block bootstrap
    95% interval (``boot_low``, ``boot_high``) and a short thick translucent bar under the
    dot over its Fisher-z interval (``fisher_low``, ``fisher_high``), which assumes
    independent pixels: where it hides under the dot, the pixels alone would claim a far
    narrower interval than the bootstrap gives. A vertical line marks :math:`\\rho = 0`.

    Rows with a non-finite ``rho`` are left out (their method keeps its row); a missing
    bound gives no bar on its side; a panel with nothing to draw says "no data", or is left
    out with ``drop_empty`` (with no data at all the first panel stays and says so). Rows of
    regions not in ``region_order`` are ignored.

    Parameters
    ----------
    rows : list of dict
        The correlation rows of every scene (``scene``, ``region``, ``method``, ``rho``,
        ``boot_low``, ``boot_high``, ``fisher_low``, ``fisher_high``; optionally ``spp``).
    spp : int, keyword-only, optional
        Keep only the rows at this SPP (rows without an ``spp`` are kept).
    title : str, keyword-only
        Figure title.
    region_order : sequence of str, keyword-only
        The regions, one panel each, left to right.
    drop_empty : bool, keyword-only
        Leave out the panels of regions without a finite ``rho``.

    Returns
    -------
    matplotlib.figure.Figure
        One axes per region in ``region_order`` (with ``drop_empty``: per region with data).
        Each holds one
        :class:`~matplotlib.container.ErrorbarContainer` per scene with data (sorted by
        scene, labelled by it; x: rho, y: method row plus the scene's offset) and one
        :class:`~matplotlib.collections.LineCollection` of its Fisher-z intervals, labelled
        ``"_fisher <scene>"``. One figure legend below: the scenes and the two intervals.
    """
    from matplotlib.lines import Line2D

    plt = _pyplot()
    region_order = tuple(region_order)
    if spp is not None:
        rows = [r for r in rows if _finite(r.get("spp", spp)) == float(spp)]
    rows = [r for r in rows if r["region"] in region_order]
    if drop_empty:
        region_order = _with_data(
            region_order, {r["region"] for r in rows if math.isfinite(_finite(r.get("rho")))}
        )
        rows = [r for r in rows if r["region"] in region_order]
    present = {r["method"] for r in rows}
    methods = [m for m in (*STATISTICS, *CONTROLS) if m in present]
    methods += sorted(present - set(methods))
    row_of = {m: k for k, m in enumerate(methods)}
    scenes = sorted({str(r.get("scene", "")) for r in rows})
    offsets = dict(zip(scenes, _dot_offsets(len(scenes)), strict=True))
    colours = {s: plt.get_cmap("tab10")(i % 10) for i, s in enumerate(scenes)}
    fig, axes = plt.subplots(
        1,
        len(region_order),
        figsize=(max(4.2 * len(region_order), 7.0), 0.42 * max(len(methods), 4) + 1.8),
        sharey=True,
        constrained_layout=True,
        squeeze=False,
    )
    axes = list(axes[0])
    n_statistics = sum(m in STATISTICS for m in methods)
    for ax, region in zip(axes, region_order, strict=True):
        drawn = False
        for scene in scenes:
            pts = sorted(
                (
                    row_of[r["method"]],
                    _finite(r.get("rho")),
                    _finite(r.get("boot_low")),
                    _finite(r.get("boot_high")),
                    _finite(r.get("fisher_low")),
                    _finite(r.get("fisher_high")),
                )
                for r in rows
                if r["region"] == region
                and str(r.get("scene", "")) == scene
                and math.isfinite(_finite(r.get("rho")))
            )
            if not pts:
                continue
            k, rho, low, high, f_low, f_high = (
                np.array(c, dtype=np.float64) for c in zip(*pts, strict=True)
            )
            y = k + offsets[scene]
            colour = colours[scene]
            has_fisher = np.isfinite(f_low) & np.isfinite(f_high)
            ax.hlines(
                y[has_fisher],
                f_low[has_fisher],
                f_high[has_fisher],
                colors=[colour],
                linewidth=5,
                alpha=0.45,
                zorder=2,
                label=f"_fisher {scene}",
            )
            ax.errorbar(
                rho,
                y,
                xerr=_bar_extents(rho, low, high),
                fmt="o",
                markersize=3.5,
                capsize=2,
                elinewidth=0.9,
                color=colour,
                label=scene,
                zorder=3,
            )
            drawn = True
        ax.axvline(0.0, color="black", linewidth=0.8, zorder=1)
        if 0 < n_statistics < len(methods):
            ax.axhline(n_statistics - 0.5, color="grey", linewidth=0.8, linestyle="--")
        ax.set_yticks(range(len(methods)), labels=[m.replace("_", "-") for m in methods])
        for tick, method in zip(ax.get_yticklabels(), methods, strict=False):
            if method not in STATISTICS:
                tick.set_color("dimgrey")
        ax.set_ylim(max(len(methods), 1) - 0.5, -0.5)
        ax.set_xlabel(r"$\rho$")
        ax.set_title(REGION_LABELS.get(region, region))
        ax.grid(True, axis="x", alpha=0.3)
        if not drawn:
            _no_data(ax)
    if n_statistics and n_statistics < len(methods):
        axes[0].set_ylabel("statistics (above dashed line), controls (grey)")
    if any(ax.containers for ax in axes):
        handles = {}
        for ax in axes:
            for c in ax.containers:
                handles.setdefault(c.get_label(), c)
        labels = sorted(handles)
        proxies = [
            Line2D([], [], color="black", linewidth=0.9, marker="|", markersize=6),
            Line2D([], [], color="black", linewidth=5, alpha=0.45),
        ]
        fig.legend(
            [handles[s] for s in labels] + proxies,
            labels + ["block bootstrap 95%", "Fisher-z 95% (independent pixels)"],
            loc="outside lower center",
            ncols=min(len(labels) + 2, 2 * len(axes) + 1),
            fontsize="small",
        )
    if title:
        fig.suptitle(wrap_to_width(title, fig.get_figwidth(), fontsize=_suptitle_size()))
    return fig
