"""The estimator validation figure: the moments estimator against N seeds.

Pure like :mod:`stereovar.figures.rho_vs_spp`: rows in (dicts as
:func:`stereovar.io.tables.read_rows` gives them), a matplotlib figure out.
"""

from __future__ import annotations

import math

import numpy as np

from .plotting import _finite, _pyplot, _statistic_label
from .uncertainty import CONTROLS, STATISTICS

FIELD_SERIES = (
    ("spearman", "moments vs seeds, Spearman", "#1f3b73", "o"),
    ("pearson", "moments vs seeds, Pearson", "#dd8452", "s"),
    (
        "reference_reliability_spearman",
        "seeds' own split-half reliability, Spearman",
        "#55a868",
        "^",
    ),
    ("reference_reliability_pearson", "seeds' own split-half reliability, Pearson", "#c44e52", "v"),
)
"""Columns of the field-agreement panel: key, label, colour, marker."""


def estimator_figure(field_rows, stat_rows, *, region: str = "all"):
    """Two panels: how the fields agree, and every statistic by both estimators.

    Left: per scene and view, the Spearman and Pearson correlation of the moment field
    with the N-seed reference, beside the reference's own split-half reliability (how well
    two independent N-seed estimates would agree), and the mean-level ratio with its
    interval on a second axis. Right: per statistic and control in ``region``, the mean
    over scenes of :math:`\\rho` by each estimator (filled) and of the attenuation-corrected
    :math:`\\rho` (hollow), with the range over scenes of the bootstrap intervals' centres
    as bars.

    Parameters
    ----------
    field_rows : list of dict
        Rows of ``estimator_fields`` (per scene and view).
    stat_rows : list of dict
        Rows of ``estimators`` (per scene, region and method).
    region : str, keyword-only

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot()
    fig, (ax_f, ax_s) = plt.subplots(1, 2, figsize=(13, 5.2), layout="constrained")
    fields = [r for r in field_rows if r.get("scene") != "mean"]
    labels = [f"{r['scene']}\n{r['view']}" for r in fields]
    x = np.arange(len(fields))
    for k, (key, label, colour, marker) in enumerate(FIELD_SERIES):
        values = [_finite(r.get(key)) for r in fields]
        ax_f.plot(x + (k - 1.5) * 0.08, values, marker, color=colour, label=label, ls="none")
    turn = {"rotation": 45, "ha": "right", "rotation_mode": "anchor"} if len(fields) > 4 else {}
    ax_f.set_xticks(x, labels, fontsize="x-small", **turn)
    ax_f.set_ylabel("correlation over the view's pixels")
    ax_f.set_ylim(min(0.0, *[v for r in fields for v in _values(r)]) - 0.05, 1.02)
    ax_f.grid(True, axis="y", alpha=0.3)
    ratio_ax = ax_f.twinx()
    ratio = np.array([_finite(r.get("mean_ratio")) for r in fields])
    low = np.array([_finite(r.get("ratio_low")) for r in fields])
    high = np.array([_finite(r.get("ratio_high")) for r in fields])
    ok = np.isfinite(ratio) & np.isfinite(low) & np.isfinite(high)
    ratio_ax.errorbar(
        x[ok] + 0.24,
        ratio[ok],
        yerr=[ratio[ok] - low[ok], high[ok] - ratio[ok]],
        fmt="D",
        color="0.4",
        ms=4,
        capsize=2,
        label="mean level, moments / seeds (95% interval)",
    )
    ratio_ax.axhline(1.0, color="0.4", lw=0.8, ls=":")
    ratio_ax.set_ylabel("mean-level ratio")
    handles = ax_f.get_legend_handles_labels()
    more = ratio_ax.get_legend_handles_labels()
    ax_f.legend(handles[0] + more[0], handles[1] + more[1], fontsize="x-small", loc="lower left")
    ax_f.set_title("the variance fields: one render against N seeds")

    names = [m for m in (*STATISTICS, *CONTROLS) if any(r["method"] == m for r in stat_rows)]
    y = np.arange(len(names))
    rows = [r for r in stat_rows if r.get("region") == region and r.get("scene") != "mean"]
    for offset, estimator, colour in ((-0.15, "seeds", "#1f3b73"), (0.15, "moments", "#dd8452")):
        for key, filled in ((f"{estimator}_rho", True), (f"{estimator}_corrected", False)):
            means, spans = [], []
            for name in names:
                values = [_finite(r.get(key)) for r in rows if r["method"] == name]
                values = [v for v in values if math.isfinite(v)]
                means.append(np.mean(values) if values else math.nan)
                spans.append((min(values), max(values)) if values else (math.nan, math.nan))
            means = np.array(means)
            lo = np.array([s[0] for s in spans])
            hi = np.array([s[1] for s in spans])
            ok = np.isfinite(means)
            shift = offset + (0.0 if filled else 0.07)
            ax_s.errorbar(
                means[ok],
                y[ok] + shift,
                # the mean of equal values can round past them: no negative bar
                xerr=np.maximum([means[ok] - lo[ok], hi[ok] - means[ok]], 0.0),
                fmt="o",
                color=colour,
                mfc=colour if filled else "white",
                ms=5,
                capsize=2,
                label=f"{estimator}" + ("" if filled else ", attenuation-corrected"),
            )
    ax_s.axvline(0.0, color="0.5", lw=0.8)
    ax_s.set_yticks(y, [_statistic_label(n) for n in names], fontsize="small")
    ax_s.invert_yaxis()
    ax_s.set_xlabel(f"rho ({region}); mean over scenes, bars: range over scenes")
    ax_s.legend(fontsize="x-small", loc="lower right")
    ax_s.grid(True, axis="x", alpha=0.3)
    ax_s.set_title("every statistic and control by both estimators")
    return fig


def _values(row) -> list[float]:
    values = [_finite(row.get(key)) for key, *_ in FIELD_SERIES]
    return [v for v in values if math.isfinite(v)]
