"""The mitigation trade-off figure: the Monte Carlo-specific cue each mitigation ships against
its image quality, beside the calibration's margin."""

from __future__ import annotations

import math

from .layout import place_labels, wrap_to_width
from .plotting import _pyplot

SHIPPED = "shipped"
"""The first panel's column: the Monte Carlo-specific :math:`\\rho` of what the mitigation
ships (``shipped_mc_specific`` where a seed-mean transform ships one image, else
``mc_specific``), read against its own margin (``margin``)."""

PANELS = (
    (SHIPPED, "all", "Monte Carlo-specific $\\rho$ of what ships (minus its matched null), "
     "all pixels"),
    ("cs_lift", "non_glass", "$C_\\sigma$ WTA accuracy over chance, non-glass"),
    ("residual_rho_zero", "all", "residual correlation at zero disparity, all pixels"),
)
"""(column, region, axis label) of each panel's y axis; x is PSNR over all pixels."""


def _float(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def _point(rows, mitigation, column, region):
    """``(value, low, high)`` of ``column`` for one mitigation and region; for
    :data:`SHIPPED`, what it ships (see there)."""
    for r in rows:
        if r["mitigation"] == mitigation and r["region"] == region:
            if column == SHIPPED:
                shipped = math.isfinite(_float(r.get("shipped_mc_specific")))
                column = "shipped_mc_specific" if shipped else "mc_specific"
            return tuple(_float(r.get(k)) for k in (column, f"{column}_low", f"{column}_high"))
    return (math.nan, math.nan, math.nan)


def _margin(rows, mitigation) -> float:
    return next((_float(r.get("margin")) for r in rows
                 if r["mitigation"] == mitigation and r["region"] == "all"), math.nan)


def _has_points(rows, names, column, region) -> bool:
    return any(math.isfinite(_point(rows, n, "psnr", "all")[0])
               and math.isfinite(_point(rows, n, column, region)[0]) for n in names)


def tradeoff_figure(rows: list[dict]):
    """One point per mitigation: the cue it leaves (y) against its PSNR (x), each with its
    95% interval as error bars (:mod:`stereovar.statistics.mitigations` states the methods),
    one panel per cue measure (:data:`PANELS`) that has a finite point (a panel with none,
    such as the non-glass lift without a material mask, is left out). The first panel is
    the Monte Carlo-specific :math:`\\rho` of what each mitigation ships, with its
    calibration margin as a grey band behind the point and the smallest cue the rules call
    (:data:`~stereovar.calibration.rules.MIN_EFFECT`) as a red dotted line: the cue is
    removed where the whole interval lies inside the band, and remains where it lies above
    the line (:func:`stereovar.statistics.mitigations.mc_cue_state`). Each point is labelled
    by its mitigation where the label
    collides with no other (:func:`stereovar.figures.layout.place_labels`, with a leader
    line when it sits farther out); the legend below names every mitigation by colour.

    Parameters
    ----------
    rows : list of dict
        :data:`stereovar.statistics.mitigations.MITIGATION_COLUMNS` rows.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot()
    names = list(dict.fromkeys(r["mitigation"] for r in rows))
    colours = plt.get_cmap("tab10")
    panels = [p for p in PANELS if p[0] == SHIPPED or _has_points(rows, names, p[0], p[1])]
    fig, axes = plt.subplots(
        1, len(panels), figsize=(5.0 * len(panels), 4.8), squeeze=False, layout="constrained"
    )
    drawn = []
    for ax, (column, region, label) in zip(axes[0], panels, strict=True):
        points = []
        for k, name in enumerate(names):
            x, x_lo, x_hi = _point(rows, name, "psnr", "all")
            y, y_lo, y_hi = _point(rows, name, column, region)
            if not (math.isfinite(x) and math.isfinite(y)):
                continue
            xerr = [[x - x_lo], [x_hi - x]] if math.isfinite(x_lo + x_hi) else None
            yerr = [[y - y_lo], [y_hi - y]] if math.isfinite(y_lo + y_hi) else None
            margin = _margin(rows, name) if column == SHIPPED else math.nan
            if math.isfinite(margin):
                ax.fill_between([x - 0.4, x + 0.4], -margin, margin, color="0.85", lw=0,
                                zorder=0)
            ax.errorbar(
                x, y, xerr=xerr, yerr=yerr, fmt="o", color=colours(k % 10), capsize=3, label=name
            )
            points.append(((x, y), name, colours(k % 10)))
        ax.axhline(0.0, color="0.5", lw=0.8, ls="--")
        if column == SHIPPED:
            from ..calibration.rules import MIN_EFFECT

            ax.axhline(MIN_EFFECT, color="#c0392b", lw=0.8, ls=":")
        ax.margins(y=0.25)  # room for the labels above and below the points
        ax.set_xlabel("PSNR against the converged reference [dB]")
        ax.set_ylabel(wrap_to_width(label, 3.6, fontsize=10.0))
        if not points:
            ax.text(0.5, 0.5, "no finite values", ha="center", va="center", transform=ax.transAxes)
        drawn.append((ax, points))
    handles, labels = axes[0][0].get_legend_handles_labels()
    if handles:
        fig.legend(
            handles, labels, loc="outside lower center", ncols=min(len(labels), 6), fontsize=8
        )
    fig.suptitle(wrap_to_width(
        "Mitigations: the cue they ship against the image quality (95% intervals; grey: "
        "each one's margin, inside which the cue counts as removed; red dotted: above it, "
        "the cue remains)", 5.0 * len(panels) - 0.4,
        fontsize=12.0))
    fig.canvas.draw()  # the layout is final: the labels are placed in it
    for ax, points in drawn:
        if points:
            xy, names_, colours_ = zip(*points, strict=True)
            place_labels(ax, xy, names_, colors=colours_, fontsize=8, draw=False)
    return fig
