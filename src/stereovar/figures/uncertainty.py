"""Figures of the uncertainty and the controls: rho against the number of seeds, and every
statistic and control per scene with its bootstrap interval."""

from __future__ import annotations

import math

import numpy as np

from .paper import REGION_COLOURS, REGION_LABELS, REGIONS, _finite, _pyplot

STATISTICS = ("warp", "spearman", "log", "trimmed")
"""The statistics of the dot plot, above the controls."""

CONTROLS = ("no_warp", "null_shift", "null_flip", "partial", "relative", "sensor", "sensor_sim")
"""The controls of the dot plot, in this order."""


def _no_data(ax) -> None:
    ax.text(0.5, 0.5, "no data", ha="center", va="center", transform=ax.transAxes)


def rho_vs_seeds_figure(curve_rows, *, title: str = "", methods=("warp", "log")):
    """:math:`\\rho` against the number of seeds :math:`N'` of Eq. 1, per region.

    One panel per region; per statistic, the mean over scenes of :math:`\\rho` from disjoint
    subsets of :math:`N'` seeds with the spread over scenes as error bars, and a dotted line
    at the mean attenuation-corrected :math:`\\rho` of the full estimate,
    :math:`\\rho / \\sqrt{r_L r_R}` (:mod:`stereovar.statistics.reliability`): the level the
    curve tends to as the estimator noise vanishes.

    Parameters
    ----------
    curve_rows : list of dict
        Rows of ``tables/seed_curve.csv``: ``region``, ``method``, ``n_prime``,
        ``mean_rho``, ``std_rho``, ``mean_rho_corrected``.
    title : str, keyword-only
    methods : sequence of str, keyword-only
        Statistics drawn (solid, dashed, ...).

    Returns
    -------
    matplotlib.figure.Figure
        One axes per region; each holds one errorbar container per drawn statistic and one
        horizontal line (label starting ``asymptote``) per statistic with a finite corrected
        :math:`\\rho`.
    """
    plt = _pyplot()
    fig, axes = plt.subplots(
        1, len(REGIONS), figsize=(11, 3.6), sharey=True, constrained_layout=True
    )
    styles = ("-", "--", ":", "-.")
    for ax, region in zip(axes, REGIONS, strict=True):
        drawn = False
        ticks = set()
        for k, method in enumerate(methods):
            pts = sorted(
                (
                    _finite(r["n_prime"]),
                    _finite(r["mean_rho"]),
                    _finite(r.get("std_rho")),
                    _finite(r.get("mean_rho_corrected")),
                )
                for r in curve_rows
                if r["region"] == region
                and r["method"] == method
                and math.isfinite(_finite(r["mean_rho"]))
                and _finite(r["n_prime"]) > 0
            )
            if not pts:
                continue
            n, rho, std, corrected = (
                np.asarray(c, dtype=np.float64) for c in zip(*pts, strict=True)
            )
            ticks.update(n.tolist())
            ax.errorbar(
                n,
                rho,
                yerr=np.where(np.isfinite(std), std, 0.0),
                marker="o",
                markersize=4,
                capsize=3,
                linestyle=styles[k % len(styles)],
                color=REGION_COLOURS[region],
                label=f"{method.replace('_', '-')}",
            )
            asymptote = corrected[np.isfinite(corrected)]
            if asymptote.size:
                ax.axhline(
                    float(asymptote[0]),
                    color=REGION_COLOURS[region],
                    linewidth=1.0,
                    linestyle=":",
                    alpha=0.8,
                    label=f"asymptote, {method} (reliability-corrected)",
                )
            drawn = True
        ax.set_xscale("log", base=2)
        if ticks:
            ax.set_xticks(sorted(ticks), labels=[f"{t:g}" for t in sorted(ticks)])
            ax.minorticks_off()
        ax.set_xlabel("seeds N' in Eq. 1")
        ax.set_title(REGION_LABELS[region])
        ax.grid(True, alpha=0.3)
        if drawn:
            ax.legend(fontsize="x-small")
        else:
            _no_data(ax)
    axes[0].set_ylabel(r"$\rho$ (mean over scenes)")
    if title:
        fig.suptitle(title)
    return fig


def statistics_dot_figure(rows, *, title: str = ""):
    """Every statistic and control per scene: :math:`\\rho` with its 95% bootstrap interval.

    One panel per region; one row per statistic (the statistics, then the controls), one
    dot per scene with a bar over its block-bootstrap interval and a short thick tick over
    its Fisher-z interval (which assumes independent pixels), and a vertical line at 0.

    Parameters
    ----------
    rows : list of dict
        The correlation rows of every scene at one SPP (``scene``, ``region``, ``method``,
        ``rho``, ``boot_low``, ``boot_high``, ``fisher_low``, ``fisher_high``).
    title : str, keyword-only

    Returns
    -------
    matplotlib.figure.Figure
        One axes per region; each holds one errorbar container per scene with data.
    """
    plt = _pyplot()
    present = {r["method"] for r in rows}
    methods = [m for m in (*STATISTICS, *CONTROLS) if m in present]
    methods += sorted(present - set(methods))
    scenes = sorted({str(r.get("scene", "")) for r in rows})
    cmap = plt.get_cmap("tab10")
    fig, axes = plt.subplots(
        1,
        len(REGIONS),
        figsize=(12, 0.35 * max(len(methods), 4) + 1.5),
        sharey=True,
        constrained_layout=True,
    )
    for ax, region in zip(axes, REGIONS, strict=True):
        drawn = False
        for s, scene in enumerate(scenes):
            pts = []
            for k, method in enumerate(methods):
                for r in rows:
                    if (str(r.get("scene", "")), r["region"], r["method"]) != (
                        scene,
                        region,
                        method,
                    ):
                        continue
                    rho = _finite(r["rho"])
                    if not math.isfinite(rho):
                        continue
                    pts.append(
                        (
                            k,
                            rho,
                            _finite(r.get("boot_low")),
                            _finite(r.get("boot_high")),
                            _finite(r.get("fisher_low")),
                            _finite(r.get("fisher_high")),
                        )
                    )
            if not pts:
                continue
            k, rho, lo, hi, flo, fhi = (
                np.asarray(c, dtype=np.float64) for c in zip(*pts, strict=True)
            )
            offset = (s - (len(scenes) - 1) / 2) * 0.12
            y = k + offset
            colour = cmap(s % 10)
            ax.errorbar(
                rho,
                y,
                xerr=np.vstack(
                    [
                        np.where(np.isfinite(lo), np.maximum(rho - lo, 0), 0),
                        np.where(np.isfinite(hi), np.maximum(hi - rho, 0), 0),
                    ]
                ),
                fmt="o",
                markersize=3,
                capsize=2,
                linewidth=0.8,
                color=colour,
                label=scene,
            )
            ok = np.isfinite(flo) & np.isfinite(fhi)
            ax.hlines(y[ok], flo[ok], fhi[ok], colors=[colour], linewidth=3, alpha=0.6)
            drawn = True
        ax.axvline(0.0, color="black", linewidth=0.8)
        ax.axhline(
            len([m for m in methods if m in STATISTICS]) - 0.5,
            color="grey",
            linewidth=0.6,
            linestyle="--",
        )
        ax.set_yticks(range(len(methods)), labels=[m.replace("_", "-") for m in methods])
        ax.set_ylim(max(len(methods), 1) - 0.5, -0.5)
        ax.set_xlabel(r"$\rho$ (bar: bootstrap 95%; thick: Fisher-z)")
        ax.set_title(REGION_LABELS[region])
        ax.grid(True, axis="x", alpha=0.3)
        if not drawn:
            _no_data(ax)
    if scenes and any(ax.containers for ax in axes):
        axes[-1].legend(fontsize="x-small", loc="lower right")
    if title:
        fig.suptitle(title)
    return fig
