"""The generator figure: each generator profile's Monte Carlo-specific cue beside its matched
null, its residual coupling at zero disparity, and its image quality."""

from __future__ import annotations

import math

from .plotting import _pyplot

PANELS = (
    ("mc_specific", "Monte Carlo-specific $\\rho$\n(partial $\\rho$ minus its matched null)"),
    ("residual_rho_zero", "residual coupling\nat zero disparity"),
    ("psnr", "PSNR of one render [dB]\n(mean over scenes, Student t interval)"),
)
"""(column, axis label) of each panel, all pixels."""


def _label(row: dict) -> str:
    spp, own = int(row["spp"]), int(row["generator_spp"])
    scaled = "" if spp == own else f" of {own}"
    return f"{row['profile']}\nSPP {spp}{scaled}"


def generators_figure(rows: list[dict]):
    """One row per profile (all pixels), one panel per measure (:data:`PANELS`): the value
    with its 95% interval; the first panel also marks the matched null's partial
    :math:`\\rho` (open circle), from which the Monte Carlo-specific part is measured.

    Parameters
    ----------
    rows : list of dict
        :data:`stereovar.statistics.generators.GENERATOR_COLUMNS` rows.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.ticker import MaxNLocator

    plt = _pyplot()
    chosen = [r for r in rows if r["region"] == "all"]
    n = max(len(chosen), 1)
    fig, axes = plt.subplots(
        1, len(PANELS), figsize=(4.2 * len(PANELS), 1.0 + 0.75 * n), squeeze=False,
        sharey=True, layout="constrained",
    )
    ys = list(range(len(chosen)))[::-1]
    for ax, (column, label) in zip(axes[0], PANELS, strict=True):
        for y, r in zip(ys, chosen, strict=True):
            v, lo, hi = (float(r[k]) for k in (column, f"{column}_low", f"{column}_high"))
            if math.isfinite(v):
                err = [[v - lo], [hi - v]] if math.isfinite(lo + hi) else None
                ax.errorbar(v, y, xerr=err, fmt="o", color="C0", capsize=3)
            else:
                ax.text(0.02, y, "n/a", va="center", transform=ax.get_yaxis_transform())
            if column == "mc_specific":
                null = float(r["null_partial"])
                if math.isfinite(null):
                    ax.plot(null, y, "o", mfc="none", color="C3")
        if column != "psnr":
            ax.axvline(0.0, color="0.5", lw=0.8, ls="--")
        ax.xaxis.set_major_locator(MaxNLocator(nbins=5))
        ax.set_xlabel(label)
        ax.grid(axis="x", alpha=0.3)
    axes[0][0].set_yticks(ys, [_label(r) for r in chosen])
    axes[0][0].set_ylim(-0.6, len(chosen) - 0.4)
    if any(math.isfinite(float(r["null_partial"])) for r in chosen):
        axes[0][0].plot([], [], "o", color="C0", label="Monte Carlo-specific, 95% interval")
        axes[0][0].plot([], [], "o", mfc="none", color="C3", label="matched null's partial")
        axes[0][0].legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), fontsize=8, frameon=False)
    fig.suptitle("Generator profiles on these scenes, all pixels")
    return fig
