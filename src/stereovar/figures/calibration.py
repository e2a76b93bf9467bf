"""The calibration figure: each rule's false-positive rate on the matched nulls and its power
on the planted cue, per transform."""

from __future__ import annotations

import math

from .plotting import _pyplot


def _f(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def calibration_figure(table: list[dict], *, method: str = "partial", scope: str = "combined"):
    """Two panels for one statistic (default the intensity-controlled :math:`\\rho`): the
    power of the ``above_null`` rule against the planted strength (a multiple of what the
    renders show), one line per transform, with 95% Wilson intervals and the 80% power line;
    and the false-positive rate of ``above_null`` (the verdict) on each cue-free design
    (matched nulls, camera pipelines, and all of them together), one row each, with the 5%
    level: blue where its 95% Wilson interval shows the level, orange where the interval
    straddles it (not shown), red where it lies above
    (:func:`stereovar.calibration.rates.meets_level`).

    Parameters
    ----------
    table : list of dict
        :data:`stereovar.calibration.summary.CALIBRATION_TABLE_COLUMNS` rows.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot()
    rows = [r for r in table if r["method"] == method and r["scope"] == scope]
    transforms = list(dict.fromkeys(r["transform"] for r in rows))
    colours = plt.get_cmap("tab10")
    bars = [
        r
        for r in rows
        if r["check"] == "false_positive_rate" and r["rule"] == "above_null"
        and math.isfinite(_f(r["value"]))
    ]
    fig, (power_ax, fpr_ax) = plt.subplots(
        1, 2, figsize=(11.0, max(4.2, 1.6 + 0.17 * len(bars))),
        gridspec_kw={"width_ratios": [1.2, 1.0]},
    )
    for k, name in enumerate(transforms):
        points = sorted(
            (_f(r["strength_factor"]), _f(r["value"]), _f(r["low"]), _f(r["high"]))
            for r in rows
            if r["transform"] == name and r["check"] == "power"
        )
        if not points:
            continue
        x, y, lo, hi = zip(*points, strict=True)
        power_ax.errorbar(
            x,
            y,
            yerr=[[a - b for a, b in zip(y, lo, strict=True)],
                  [b - a for a, b in zip(y, hi, strict=True)]],
            fmt="o-",
            color=colours(k % 10),
            capsize=3,
            label=name,
        )
    power_ax.axhline(0.8, color="0.5", lw=0.8, ls="--")
    power_ax.set_xscale("log", base=2)
    factors = sorted({_f(r["strength_factor"]) for r in rows if r["check"] == "power"})
    if factors:
        power_ax.set_xticks(factors)
        power_ax.set_xticklabels([f"{f:g}" for f in factors])
        power_ax.minorticks_off()
    power_ax.set_ylim(-0.03, 1.03)
    power_ax.set_xlabel("planted strength (x what the renders show)")
    power_ax.set_ylabel("power (above its matched null)")
    power_ax.set_title("Detects a planted cue", fontsize=10)
    if transforms:
        # beside the axes: the points sit at 0 and 1 across every strength, so no corner is free
        power_ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    from ..calibration.rates import meets_level
    from ..calibration.summary import ANY_NULL

    # whether the 5% level is shown (the whole interval at or below it), refuted (above it)
    # or not shown (the interval straddles it: too few replicates to tell)
    colours_by_word = {"yes": "tab:blue", "no": "tab:red"}
    labels = []
    for i, r in enumerate(bars):
        value = _f(r["value"])
        colour = colours_by_word.get(meets_level(r["low"], r["high"]), "tab:orange")
        pooled = r["kind"] == ANY_NULL
        fpr_ax.errorbar(
            value,
            i,
            xerr=[[value - _f(r["low"])], [_f(r["high"]) - value]],
            fmt="D" if pooled else "s",
            mfc=colour,
            color=colour,
            capsize=2,
            ms=5 if pooled else 4,
        )
        n = _f(r.get("n"))
        labels.append(f"{r['transform']}: {r['kind']}" + (f" (n={n:.0f})" if math.isfinite(n)
                                                          else ""))
    fpr_ax.axvline(0.05, color="0.5", lw=0.8, ls="--")
    fpr_ax.set_yticks(range(len(bars)))
    fpr_ax.set_yticklabels(labels, fontsize=7)
    fpr_ax.invert_yaxis()
    fpr_ax.set_xlim(-0.02, 1.02)
    fpr_ax.set_xlabel("false-positive rate (95% Wilson interval)")
    fpr_ax.set_title(
        "Calls a cue on data without one\n(blue: 5% shown; orange: not shown;\nred: refuted)",
        fontsize=9,
    )
    fig.suptitle(f"Calibration of {method} on synthetic frames from this run", fontsize=11)
    fig.tight_layout()
    return fig
