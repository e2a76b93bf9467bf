"""The probe figure, one row of panels per architecture: the accuracy of each training
condition's networks on each test input, and the power curve of the planted cue."""

from __future__ import annotations

import math

import numpy as np

from ..probe.inputs import TEST_INPUTS
from ..probe.metrics import planted_factor
from .plotting import _pyplot


def _errorbar(ax, xs, rows, key, **style) -> None:
    """Points ``rows[key]`` at ``xs`` with their ``_low``/``_high`` interval."""
    keep = [(x, r) for x, r in zip(xs, rows, strict=True) if math.isfinite(r[key])]
    if not keep:
        return
    x = [k[0] for k in keep]
    y = np.array([k[1][key] for k in keep])
    low = np.array([k[1][f"{key}_low"] for k in keep])
    high = np.array([k[1][f"{key}_high"] for k in keep])
    ax.errorbar(x, y, yerr=np.nan_to_num([y - low, high - y]), capsize=2, **style)


def _accuracy_panel(ax, rows, colours) -> None:
    conditions = [c for c in dict.fromkeys(r["tested"] for r in rows)
                  if not math.isfinite(planted_factor(c))]
    inputs = [t for t in TEST_INPUTS if any(r["test_input"] == t for r in rows)]
    width = 0.8 / max(len(conditions), 1)
    for k, condition in enumerate(conditions):
        xs, picked = [], []
        for i, test_input in enumerate(inputs):
            row = next((r for r in rows
                        if (r["tested"], r["test_input"]) == (condition, test_input)), None)
            if row is not None:
                xs.append(i + (k - (len(conditions) - 1) / 2) * width)
                picked.append(row)
        _errorbar(ax, xs, picked, "accuracy", fmt="o", ms=4, color=colours(k % 10),
                  label=condition)
        twins = [r for r in picked if math.isfinite(r.get("twin_accuracy", math.nan))]
        if twins:
            shift = width / 3
            _errorbar(ax, [x + shift for x, r in zip(xs, picked, strict=True) if r in twins],
                      twins,
                      "twin_accuracy", fmt="x", ms=4, color=colours(k % 10), alpha=0.6)
    ax.set_xticks(range(len(inputs)))
    ax.set_xticklabels(inputs, rotation=30, ha="right", rotation_mode="anchor")
    ax.set_ylabel("accuracy (|d - d_GT| < 1 px)")
    ax.grid(axis="y", alpha=0.3)
    if conditions:
        # beside the panel: inside it, the legend would cover the points of some inputs
        ax.legend(title="trained on\n(x: its twin)", fontsize=7, title_fontsize=7,
                  loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)


def _power_panel(ax, rows) -> None:
    shuffled = [r for r in rows if r["test_input"] == "shuffled"]
    curve = sorted((r for r in shuffled if math.isfinite(planted_factor(r["tested"]))),
                   key=lambda r: planted_factor(r["tested"]))
    none = next((r for r in shuffled if r["tested"] == "none"), None)
    ax.axhline(0.0, color="0.3", lw=0.8)
    top = 1.0
    if curve:
        factors = [planted_factor(r["tested"]) for r in curve]
        top = max(factors)
        detected = [r for r in curve if r["did_low"] > 0]
        missed = [r for r in curve if not r["did_low"] > 0]
        _errorbar(ax, factors, curve, "did", fmt="-", color="C0", lw=1)
        _errorbar(ax, [planted_factor(r["tested"]) for r in detected], detected, "did",
                  fmt="o", ms=5, color="C0", label="planted, detected")
        _errorbar(ax, [planted_factor(r["tested"]) for r in missed], missed, "did",
                  fmt="o", ms=5, mfc="white", color="C0", label="planted, not detected")
        ax.axvline(1.0, color="0.6", lw=0.8, ls=":")
    if none is not None and math.isfinite(none["did"]):
        # the renders as they are, at 0 on the planted axis (nothing planted)
        _errorbar(ax, [0.0], [none], "did", fmt="s", ms=5, color="C3",
                  label="none (the renders as they are)")
        ax.axhspan(none["did_low"], none["did_high"], color="C3", alpha=0.1)
        mde = none.get("did_mde", math.nan)
        if math.isfinite(mde):
            ax.axhline(mde, color="k", ls="--", lw=1,
                       label=f"smallest detectable DiD {mde:.3g}")
    ax.set_xlim(-0.1 * top - 0.1, 1.1 * top + 0.1)
    ax.margins(y=0.15)
    ax.set_xlabel("planted strength, x the renders' strength\n(dotted: x1; 0: the renders)")
    ax.set_ylabel("DiD of the shuffle vs the twin")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def probe_figure(rows: list[dict]):
    """The probe per architecture: accuracy (``|d - d_GT| < 1`` px) of each training
    condition's networks (dots) and their cue-blind twins (crosses) on each test input, and
    the power curve: the shuffle's difference in differences against the twin for each
    planted strength, detected (filled) or not, beside the ``none`` networks' DiD (band) and
    the smallest DiD detectable at this budget (dashed). 95 % intervals over training seeds
    and test tiles (:mod:`stereovar.probe.metrics`); the verdict's region (``non_glass``
    where there is one).

    Parameters
    ----------
    rows : list of dict
        :func:`stereovar.probe.metrics.probe_rows`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot()
    regions = {r["region"] for r in rows}
    region = "non_glass" if "non_glass" in regions else "all"
    rows = [r for r in rows if r["region"] == region]
    architectures = list(dict.fromkeys(r["architecture"] for r in rows)) or ["(none)"]
    fig, axes = plt.subplots(len(architectures), 2, figsize=(11, 4.0 * len(architectures)),
                             squeeze=False, layout="constrained")
    colours = plt.get_cmap("tab10")
    for (ax_acc, ax_pow), arch in zip(axes, architectures, strict=True):
        mine = [r for r in rows if r["architecture"] == arch]
        _accuracy_panel(ax_acc, mine, colours)
        _power_panel(ax_pow, mine)
        ax_acc.set_title(f"{arch}: accuracy per test input")
        ax_pow.set_title(f"{arch}: planted cue, power")
    fig.suptitle(f"Learned probe, {region} pixels, 95% intervals (training seeds x test tiles)")
    return fig
