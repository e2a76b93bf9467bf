"""The probe figure: the trained matcher's accuracy on each test input, per training condition."""

from __future__ import annotations

import math

import numpy as np

from ..probe.inputs import TEST_INPUTS
from .paper import _pyplot


def probe_figure(rows: list[dict]):
    """Accuracy (``|d - d_GT| < 1`` px) of each training condition's networks on each test input,
    with 95% intervals over test tiles and training seeds
    (:mod:`stereovar.probe.metrics`); one panel per region. A network that uses the Monte
    Carlo cue loses more on ``shuffled`` and ``conflict`` than the ``sensor_only`` control.

    Parameters
    ----------
    rows : list of dict
        :func:`stereovar.probe.metrics.probe_rows`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot()
    regions = list(dict.fromkeys(r["region"] for r in rows))
    conditions = list(dict.fromkeys(r["training"] for r in rows))
    inputs = [t for t in TEST_INPUTS if any(r["test_input"] == t for r in rows)]
    colours = plt.get_cmap("tab10")
    fig, axes = plt.subplots(
        1, max(len(regions), 1), figsize=(5.2 * max(len(regions), 1), 4.2), squeeze=False
    )
    width = 0.8 / max(len(conditions), 1)
    for ax, region in zip(axes[0], regions, strict=False):
        for k, condition in enumerate(conditions):
            xs, ys, lo, hi = [], [], [], []
            for i, test_input in enumerate(inputs):
                row = next(
                    (
                        r
                        for r in rows
                        if (r["training"], r["test_input"], r["region"])
                        == (condition, test_input, region)
                    ),
                    None,
                )
                if row is None or not math.isfinite(row["accuracy"]):
                    continue
                xs.append(i + (k - (len(conditions) - 1) / 2) * width)
                ys.append(row["accuracy"])
                lo.append(row["accuracy"] - row["accuracy_low"])
                hi.append(row["accuracy_high"] - row["accuracy"])
            if xs:
                ax.errorbar(
                    xs,
                    ys,
                    yerr=np.nan_to_num([lo, hi]),
                    fmt="o",
                    ms=4,
                    capsize=2,
                    color=colours(k % 10),
                    label=condition,
                )
        ax.set_xticks(range(len(inputs)))
        ax.set_xticklabels(inputs, rotation=20)
        ax.set_ylabel("WTA accuracy (|d - d_GT| < 1 px)")
        ax.set_title(f"region: {region}")
        ax.grid(axis="y", alpha=0.3)
    axes[0][0].legend(title="trained on", fontsize=8)
    fig.suptitle("Learned probe: accuracy per test input, 95% intervals (tiles x training seeds)")
    fig.tight_layout()
    return fig
