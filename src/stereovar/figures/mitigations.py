"""The mitigation trade-off figure: the cue each mitigation leaves against its image quality."""

from __future__ import annotations

import math

from .layout import place_labels, wrap_to_width
from .paper import _pyplot

PANELS = (
    ("partial", "all", "intensity-controlled $\\rho$ (Monte Carlo-specific), all pixels"),
    ("cs_lift", "non_glass", "$C_\\sigma$ WTA accuracy over chance, non-glass"),
    ("residual_rho_zero", "all", "residual correlation at zero disparity, all pixels"),
)
"""(column, region, axis label) of each panel's y axis; x is PSNR over all pixels."""


def _point(rows, mitigation, column, region):
    for r in rows:
        if r["mitigation"] == mitigation and r["region"] == region:
            return (float(r[column]), float(r[f"{column}_low"]), float(r[f"{column}_high"]))
    return (math.nan, math.nan, math.nan)


def tradeoff_figure(rows: list[dict]):
    """One point per mitigation: the cue it leaves (y) against its PSNR (x), each with its
    95% interval as error bars (:mod:`stereovar.statistics.mitigations` states the methods),
    one panel per cue measure (:data:`PANELS`). A mitigation that removes the cue at no cost
    sits at the bottom right. Each point is labelled by its mitigation where the label
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
    fig, axes = plt.subplots(
        1, len(PANELS), figsize=(5.0 * len(PANELS), 4.8), squeeze=False, layout="constrained"
    )
    drawn = []
    for ax, (column, region, label) in zip(axes[0], PANELS, strict=True):
        points = []
        for k, name in enumerate(names):
            x, x_lo, x_hi = _point(rows, name, "psnr", "all")
            y, y_lo, y_hi = _point(rows, name, column, region)
            if not (math.isfinite(x) and math.isfinite(y)):
                continue
            xerr = [[x - x_lo], [x_hi - x]] if math.isfinite(x_lo + x_hi) else None
            yerr = [[y - y_lo], [y_hi - y]] if math.isfinite(y_lo + y_hi) else None
            ax.errorbar(
                x, y, xerr=xerr, yerr=yerr, fmt="o", color=colours(k % 10), capsize=3, label=name
            )
            points.append(((x, y), name, colours(k % 10)))
        ax.axhline(0.0, color="0.5", lw=0.8, ls="--")
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
    fig.suptitle("Mitigations: the cue they leave against the image quality (95% intervals)")
    fig.canvas.draw()  # the layout is final: the labels are placed in it
    for ax, points in drawn:
        if points:
            xy, names_, colours_ = zip(*points, strict=True)
            place_labels(ax, xy, names_, colors=colours_, fontsize=8, draw=False)
    return fig
