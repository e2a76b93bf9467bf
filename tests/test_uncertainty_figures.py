"""The rho-against-seeds and statistics dot figures draw exactly their input rows."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import pytest

from stereovar.figures.plotting import REGION_LABELS, REGIONS
from stereovar.figures.uncertainty import (
    ASYMPTOTE_LABEL,
    CONTROLS,
    STATISTICS,
    rho_vs_seeds_figure,
    statistics_dot_figure,
)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _bar_ends(container, axis: int) -> list[tuple[float, float]]:
    """(low, high) of each error segment of an errorbar container along ``axis`` (0: x)."""
    (bars,) = container.lines[2]
    return [tuple(sorted(seg[:, axis])) for seg in bars.get_segments()]


# --- rho against N' ---------------------------------------------------------------------

N_PRIME = (2, 4, 8, 16)
CORRECTED = {
    (region, method): 0.9 + 0.01 * i + 0.03 * j
    for i, region in enumerate(REGIONS)
    for j, method in enumerate(("warp", "log"))
}


def _curve_rows():
    rows = []
    for i, region in enumerate(REGIONS):
        for j, method in enumerate(("warp", "log")):
            for n in N_PRIME:
                rows.append(
                    {
                        "region": region,
                        "method": method,
                        "n_prime": n,
                        "mean_rho": 0.2 + 0.1 * i + 0.05 * j + 0.04 * math.log2(n),
                        "std_rho": 0.01 * n,
                        "n_scenes": 4,
                        "mean_rho_corrected": CORRECTED[region, method],
                    }
                )
    rows[3]["std_rho"] = math.nan  # all, warp, N' = 16: no bar
    rows[4]["mean_rho"] = math.nan  # all, log, N' = 2: left out
    rows.append({**rows[0], "n_prime": math.nan})  # no N': left out
    rows.append({**rows[0], "method": "spearman"})  # not drawn by default
    return rows


def _expected(rows, region, method):
    return sorted(
        (
            r
            for r in rows
            if (r["region"], r["method"]) == (region, method)
            and math.isfinite(r["n_prime"])
            and math.isfinite(r["mean_rho"])
        ),
        key=lambda r: r["n_prime"],
    )


def test_rho_vs_seeds_draws_the_means_and_their_spread_over_scenes():
    rows = _curve_rows()
    fig = rho_vs_seeds_figure(rows)
    assert len(fig.axes) == len(REGIONS)
    for ax, region in zip(fig.axes, REGIONS, strict=True):
        assert ax.get_title() == f"{REGION_LABELS[region]} (4 scenes)"
        containers = ax.containers
        assert len(containers) == 2  # warp and log; spearman is not asked for
        for container, method, style in zip(containers, ("warp", "log"), ("-", "--"), strict=True):
            expected = _expected(rows, region, method)
            line = container.lines[0]
            x, y = line.get_data()
            np.testing.assert_array_equal(x, [r["n_prime"] for r in expected])
            np.testing.assert_allclose(y, [r["mean_rho"] for r in expected])
            assert line.get_linestyle() == style
            ends = _bar_ends(container, axis=1)
            assert len(ends) == len(expected)
            for (low, high), r in zip(ends, expected, strict=True):
                std = r["std_rho"] if math.isfinite(r["std_rho"]) else 0.0
                assert (low, high) == pytest.approx((r["mean_rho"] - std, r["mean_rho"] + std))
    # the NaN mean is left out, the NaN spread has a zero-length bar
    assert list(fig.axes[0].containers[1].lines[0].get_xdata()) == [4, 8, 16]
    low, high = _bar_ends(fig.axes[0].containers[0], axis=1)[-1]
    assert low == high


def test_rho_vs_seeds_asymptote_is_the_mean_corrected_rho():
    fig = rho_vs_seeds_figure(_curve_rows())
    for ax, region in zip(fig.axes, REGIONS, strict=True):
        lines = [ln for ln in ax.get_lines() if ln.get_label().startswith(ASYMPTOTE_LABEL)]
        assert len(lines) == 2
        for line, method, container in zip(lines, ("warp", "log"), ax.containers, strict=True):
            y = line.get_ydata()
            np.testing.assert_allclose(y, [CORRECTED[region, method]] * 2)
            np.testing.assert_array_equal(line.get_xdata(), [0, 1])  # spans the axes
            assert line.get_linestyle() == ":"
            assert line.get_color() == container.lines[0].get_color()
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels[:2] == ["Pearson (Eq. 3)", r"Pearson of $\ln\sigma^2$"]
    assert all(label.startswith(ASYMPTOTE_LABEL) for label in labels[2:])


def test_rho_vs_seeds_axis_is_log2_with_ticks_at_each_n_prime():
    fig = rho_vs_seeds_figure(_curve_rows(), title="curve")
    for ax in fig.axes:
        assert ax.get_xscale() == "log"
        assert ax.xaxis.get_transform().base == 2
        np.testing.assert_array_equal(ax.get_xticks(), N_PRIME)
        assert [t.get_text() for t in ax.get_xticklabels()] == [str(n) for n in N_PRIME]
    assert fig.get_suptitle() == "curve"
    fig.canvas.draw()


def test_rho_vs_seeds_region_order_and_missing_panels():
    rows = [r for r in _curve_rows() if r["region"] != "glass"]
    fig = rho_vs_seeds_figure(rows, region_order=("glass", "non_glass"))
    glass, non_glass = fig.axes
    assert glass.get_title() == "glass"
    assert [t.get_text() for t in glass.texts] == ["no data"]
    assert non_glass.get_title().startswith("non-glass")
    assert not non_glass.texts and len(non_glass.containers) == 2


def test_rho_vs_seeds_asymptote_without_a_curve_and_nan_corrected():
    rows = [
        {"region": "all", "method": "warp", "n_prime": 8, "mean_rho": math.nan,
         "std_rho": math.nan, "mean_rho_corrected": 0.97},
        {"region": "glass", "method": "warp", "n_prime": 8, "mean_rho": 0.5,
         "std_rho": 0.1, "mean_rho_corrected": math.nan},
    ]  # fmt: skip
    fig = rho_vs_seeds_figure(rows)
    everything, non_glass, glass = fig.axes
    assert not everything.containers and not everything.texts
    (line,) = everything.get_lines()
    assert line.get_ydata()[0] == pytest.approx(0.97)
    assert [t.get_text() for t in non_glass.texts] == ["no data"]
    assert len(glass.containers) == 1
    assert not [ln for ln in glass.get_lines() if ln.get_label().startswith(ASYMPTOTE_LABEL)]
    fig.canvas.draw()


def test_rho_vs_seeds_without_rows_says_no_data():
    fig = rho_vs_seeds_figure([])
    assert len(fig.axes) == 3
    assert all([t.get_text() for t in ax.texts] == ["no data"] for ax in fig.axes)
    assert not fig.legends
    fig.canvas.draw()


# --- statistics dot plot ----------------------------------------------------------------

SCENES = ("scene_b", "scene_a")
DOT_METHODS = ("sensor_sim", "warp", "custom", "no_warp", "spearman")


def _dot_rows():
    rows = []
    for s, scene in enumerate(SCENES):
        for i, region in enumerate(REGIONS):
            for k, method in enumerate(DOT_METHODS):
                rho = 0.1 * k + 0.01 * s + 0.001 * i
                rows.append(
                    {
                        "scene": scene,
                        "spp": 32,
                        "region": region,
                        "method": method,
                        "rho": rho,
                        "boot_low": rho - 0.05,
                        "boot_high": rho + 0.1,
                        "fisher_low": rho - 0.002,
                        "fisher_high": rho + 0.001,
                    }
                )
                # another SPP of the same scene, to be filtered out
                rows.append({**rows[-1], "spp": 64, "rho": -0.5})
    for r in rows:
        if (r["scene"], r["region"], r["method"]) == ("scene_a", "glass", "sensor_sim"):
            r["rho"] = math.nan
        if (r["scene"], r["region"], r["method"]) == ("scene_a", "all", "warp"):
            r["boot_high"] = math.nan
            r["fisher_low"] = math.nan
    return rows


ORDER = ["warp", "spearman", "no_warp", "sensor_sim", "custom"]


def _points(rows, scene, region):
    """(row index, rho, row) of the drawn points of one scene and region, in plot order."""
    pts = [
        (ORDER.index(r["method"]), r["rho"], r)
        for r in rows
        if (r["scene"], r["region"], r["spp"]) == (scene, region, 32) and math.isfinite(r["rho"])
    ]
    return sorted(pts, key=lambda p: p[0])


def test_dot_figure_orders_statistics_then_controls_then_others():
    fig = statistics_dot_figure(_dot_rows(), spp=32)
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert labels == [m.replace("_", "-") for m in ORDER]
    assert set(ORDER[:2]) <= set(STATISTICS) and set(ORDER[2:4]) <= set(CONTROLS)
    # the separator below the statistics and the zero line
    horizontal = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
    assert [ln.get_ydata()[0] for ln in horizontal] == [1.5]
    zero = [ln for ln in ax.get_lines() if list(ln.get_xdata()) == [0, 0]]
    assert len(zero) == 1
    assert ax.get_ylim() == (4.5, -0.5)  # first method on top


def test_dot_figure_draws_each_scene_rho_and_both_intervals():
    rows = _dot_rows()
    fig = statistics_dot_figure(rows, spp=32)
    for ax, region in zip(fig.axes, REGIONS, strict=True):
        assert ax.get_title() == REGION_LABELS[region]
        containers = {c.get_label(): c for c in ax.containers}
        assert list(containers) == sorted(SCENES)
        fisher = {c.get_label(): c for c in ax.collections if c.get_label().startswith("_fisher")}
        ys = {}
        for scene in SCENES:
            pts = _points(rows, scene, region)
            x, y = containers[scene].lines[0].get_data()
            np.testing.assert_allclose(x, [p[1] for p in pts])
            offset = np.asarray(y) - [p[0] for p in pts]
            np.testing.assert_allclose(offset, offset[0])
            ys[scene] = offset[0]
            for (low, high), (_, rho, r) in zip(
                _bar_ends(containers[scene], axis=0), pts, strict=True
            ):
                top = r["boot_high"] if math.isfinite(r["boot_high"]) else rho
                assert (low, high) == pytest.approx((r["boot_low"], top))
            with_fisher = [p for p in pts if math.isfinite(p[2]["fisher_low"])]
            segments = fisher[f"_fisher {scene}"].get_segments()
            assert len(segments) == len(with_fisher)
            for seg, (k, _, r) in zip(segments, with_fisher, strict=True):
                np.testing.assert_allclose(seg[:, 0], [r["fisher_low"], r["fisher_high"]])
                np.testing.assert_allclose(seg[:, 1], k + ys[scene])
        assert ys["scene_a"] < ys["scene_b"]  # scenes side by side, in name order
        colours = {containers[s].lines[0].get_color() for s in SCENES}
        assert len(colours) == 2
    # scene_a's NaN rho in glass is left out; the other rows of its method stay
    glass = {c.get_label(): c for c in fig.axes[2].containers}
    assert len(glass["scene_a"].lines[0].get_xdata()) == len(ORDER) - 1
    assert len(glass["scene_b"].lines[0].get_xdata()) == len(ORDER)
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend[:2] == sorted(SCENES)
    assert any("bootstrap" in t for t in legend) and any("Fisher" in t for t in legend)
    fig.canvas.draw()


def test_dot_figure_spp_selects_rows():
    rows = _dot_rows()
    fig = statistics_dot_figure(rows, spp=64)
    x = fig.axes[0].containers[0].lines[0].get_xdata()
    np.testing.assert_allclose(x, -0.5)
    # without spp every row is drawn: both SPPs share the method rows
    fig = statistics_dot_figure(rows, title="t")
    assert len(fig.axes[0].containers[0].lines[0].get_xdata()) == 2 * len(ORDER)
    assert fig.get_suptitle() == "t"


def test_dot_figure_empty_and_all_nan_say_no_data():
    fig = statistics_dot_figure([])
    assert [[t.get_text() for t in ax.texts] for ax in fig.axes] == [["no data"]] * 3
    assert not fig.legends
    fig.canvas.draw()
    rows = [r for r in _dot_rows() if r["region"] == "glass"]
    for r in rows:
        r["rho"] = math.nan
    fig = statistics_dot_figure(rows, spp=32)
    assert all(not ax.containers for ax in fig.axes)
    assert all([t.get_text() for t in ax.texts] == ["no data"] for ax in fig.axes)
    fig.canvas.draw()
    fig = statistics_dot_figure(_dot_rows(), spp=8)
    assert all([t.get_text() for t in ax.texts] == ["no data"] for ax in fig.axes)
