"""The rho-against-seeds and statistics dot figures draw exactly their input rows."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stereovar.figures.uncertainty import rho_vs_seeds_figure, statistics_dot_figure


def _curve():
    rows = []
    for region in ("all", "non_glass", "glass"):
        for method, base in (("warp", 0.3), ("log", 0.5)):
            for n in (2, 4, 8):
                rows.append(
                    {
                        "region": region,
                        "method": method,
                        "n_prime": n,
                        "mean_rho": base + 0.05 * n,
                        "std_rho": 0.01 * n if n < 8 else math.nan,
                        "mean_rho_corrected": 0.95,
                    }
                )
    return rows


def test_rho_vs_seeds_draws_the_means_spreads_and_the_asymptote():
    fig = rho_vs_seeds_figure(_curve())
    ax = fig.axes[0]
    warp = ax.containers[0]
    x, y = warp.lines[0].get_data()
    np.testing.assert_allclose(x, [2, 4, 8])
    np.testing.assert_allclose(y, [0.4, 0.5, 0.7])
    segments = warp.lines[2][0].get_segments()
    np.testing.assert_allclose([s[1][1] - s[0][1] for s in segments], [0.04, 0.08, 0.0])
    asymptotes = [ln for ln in ax.get_lines() if str(ln.get_label()).startswith("asymptote")]
    assert len(asymptotes) == 2
    assert asymptotes[0].get_ydata()[0] == pytest.approx(0.95)


def test_rho_vs_seeds_without_rows_says_no_data():
    fig = rho_vs_seeds_figure([])
    assert all([t.get_text() for t in ax.texts] == ["no data"] for ax in fig.axes)


def test_dot_figure_draws_each_scene_and_its_bootstrap_interval():
    rows = []
    for s, scene in enumerate(("a", "b")):
        for region in ("all", "non_glass", "glass"):
            for k, method in enumerate(("warp", "spearman", "no_warp", "sensor_sim")):
                rho = 0.1 * k + 0.01 * s
                rows.append(
                    {
                        "scene": scene,
                        "region": region,
                        "method": method,
                        "rho": rho if (region, method) != ("glass", "sensor_sim") else math.nan,
                        "boot_low": rho - 0.05,
                        "boot_high": rho + 0.1,
                        "fisher_low": rho - 0.01,
                        "fisher_high": rho + 0.01,
                    }
                )
    fig = statistics_dot_figure(rows)
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_yticklabels()] == [
        "warp",
        "spearman",
        "no-warp",
        "sensor-sim",
    ]
    first = ax.containers[0]
    x, y = first.lines[0].get_data()
    np.testing.assert_allclose(x, [0.0, 0.1, 0.2, 0.3])
    ends = [(seg[0][0], seg[1][0]) for seg in first.lines[2][0].get_segments()]
    np.testing.assert_allclose(ends, [(r - 0.05, r + 0.1) for r in (0.0, 0.1, 0.2, 0.3)])
    # a NaN rho is left out: the glass panel has three rows per scene
    assert len(fig.axes[2].containers[0].lines[0].get_xdata()) == 3
    assert [t.get_text() for t in statistics_dot_figure([]).axes[0].texts] == ["no data"]
