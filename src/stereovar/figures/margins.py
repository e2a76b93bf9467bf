"""The intervention's figure (paper Sec. 3.4): the distributions of the ground truth's
margin over the best wrong disparity, normal against decorrelated, per cost and region, on a
symmetric-log axis (:func:`symlog_ticks`).

Pure, as every figure: rows in, a matplotlib figure on the Agg backend out; the caller
saves it.
"""

from __future__ import annotations

import math

import numpy as np

from .plotting import REGION_LABELS, _finite, _pyplot


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
