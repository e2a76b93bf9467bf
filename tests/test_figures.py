"""Paper figures 1-3: the plotted data read back from the artists match the inputs."""

from __future__ import annotations

import math
import re

import matplotlib.pyplot as plt
import numpy as np
import pytest
import xarray as xr
from matplotlib.collections import PathCollection, QuadMesh
from matplotlib.colors import LogNorm, to_rgba
from matplotlib.legend import Legend

from stereovar.figures.material_scatter import (
    GLASS_COLOUR,
    NON_GLASS_COLOUR,
    material_scatter_figure,
)
from stereovar.figures.plotting import REGION_LABELS, REGIONS
from stereovar.figures.rho_vs_spp import rho_vs_spp_figure
from stereovar.figures.teaser import teaser_figure

RHO = re.compile(r"\\rho = (-?[0-9.]+)")


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _rho_in(text: str) -> float:
    m = RHO.search(text)
    assert m, f"no rho in {text!r}"
    return float(m.group(1))


def _corr(a, b) -> float:
    return float(np.corrcoef(np.asarray(a, np.float64), np.asarray(b, np.float64))[0, 1])


def _fields(height=24, width=40, seed=3):
    """Correlated log-normal variance fields with zeros, a negative value, a NaN and a mask."""
    rng = np.random.default_rng(seed)
    base = np.exp(rng.normal(0.0, 2.0, size=(height, width)))
    left = base * rng.lognormal(0.0, 0.3, size=base.shape)
    right = base * rng.lognormal(0.0, 0.3, size=base.shape)
    warped = base * rng.lognormal(0.0, 0.3, size=base.shape)
    omega = np.ones((height, width), dtype=bool)
    omega[:, -4:] = False
    omega[0, :7] = False
    left[1, :5] = 0.0
    warped[2, 3:6] = 0.0
    left[3, 0] = -1e-3
    warped[4, 4] = np.nan
    warped[~omega] = 0.0
    return left, right, warped, omega


# --- Fig. 1 -----------------------------------------------------------------------------


def test_teaser_histogram_counts_the_positive_omega_pixels():
    left, right, warped, omega = _fields()
    fig = teaser_figure(left, right, warped, omega, bins=17)
    ax = fig.axes[3]
    meshes = [c for c in ax.collections if isinstance(c, QuadMesh)]
    assert len(meshes) == 1
    counts = np.ma.filled(meshes[0].get_array(), 0.0)
    with np.errstate(invalid="ignore"):
        expected = omega & np.isfinite(warped) & (left > 0) & (warped > 0)
    assert counts.size == 17 * 17
    assert counts.sum() == expected.sum()
    assert expected.sum() < omega.sum()  # the zeros, negative and NaN were left out
    assert isinstance(meshes[0].norm, LogNorm)
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"


def test_teaser_histogram_bins_are_log_spaced_over_the_positive_range():
    left, right, warped, omega = _fields()
    bins = 9
    fig = teaser_figure(left, right, warped, omega, bins=bins)
    coords = fig.axes[3].collections[0].get_coordinates()
    xedges, yedges = coords[0, :, 0], coords[:, 0, 1]
    np.testing.assert_allclose(xedges, yedges)
    assert xedges.size == bins + 1
    np.testing.assert_allclose(np.diff(np.log(xedges)), np.log(xedges[1] / xedges[0]))
    with np.errstate(invalid="ignore"):
        pos = omega & np.isfinite(warped) & (left > 0) & (warped > 0)
    values = np.concatenate([left[pos], warped[pos]])
    np.testing.assert_allclose([xedges[0], xedges[-1]], [values.min(), values.max()])


def test_teaser_rho_in_title_is_pearson_over_omega_and_diagonal_is_red():
    left, right, warped, omega = _fields()
    left[5:8, :10] = 0.0  # Eq. 3 is over all of omega: zeros count, and here they matter
    fig = teaser_figure(left, right, warped, omega)
    ax = fig.axes[3]
    sel = omega & np.isfinite(left) & np.isfinite(warped)
    rho = _corr(left[sel], warped[sel])
    assert abs(rho - _corr(left[sel & (left > 0)], warped[sel & (left > 0)])) > 1e-3
    assert _rho_in(ax.get_title()) == pytest.approx(rho, abs=5e-5)
    diag = [ln for ln in ax.get_lines() if ln.get_label() == "$y = x$"]
    assert len(diag) == 1
    x, y = diag[0].get_data()
    np.testing.assert_allclose(x, y)
    assert to_rgba(diag[0].get_color()) == to_rgba("red")


def test_teaser_image_panels_share_robust_log_colour_limits_and_one_colour_bar():
    left, right, warped, omega = _fields()
    fig = teaser_figure(left, right, warped, omega)
    images = [ax.images[0] for ax in fig.axes[:3]]
    for im in images:
        assert isinstance(im.norm, LogNorm)
    limits = {im.get_clim() for im in images}
    assert len(limits) == 1
    shown = np.concatenate([left.ravel(), right.ravel(), warped[omega]])
    shown = shown[np.isfinite(shown) & (shown > 0)]
    np.testing.assert_allclose(limits.pop(), np.percentile(shown, [1.0, 99.5]))
    # one colour bar for (a)-(c), whose mappable uses those limits; one for (d)'s counts
    colourbars = [ax for ax in fig.axes[4:] if ax.get_label() == "<colorbar>"]
    assert len(colourbars) == 2
    # (c) is masked outside omega; (a) only where non-finite
    np.testing.assert_array_equal(
        np.ma.getmaskarray(images[2].get_array()), ~omega | np.isnan(warped)
    )
    assert not np.ma.getmaskarray(images[0].get_array()).any()
    # non-positive values render in the under colour, below vmin
    vmin = images[0].norm.vmin
    assert (images[0].get_array()[left <= 0] < vmin).all()
    np.testing.assert_allclose(images[0].get_array()[left > 0], left[left > 0])


def test_teaser_accepts_transposed_xarray_inputs():
    left, right, warped, omega = _fields()

    def da(a):
        return xr.DataArray(a, dims=("y", "x")).transpose("x", "y")

    fig_np = teaser_figure(left, right, warped, omega)
    fig_xr = teaser_figure(da(left), da(right), da(warped), da(omega))
    assert fig_np.axes[3].get_title() == fig_xr.axes[3].get_title()
    np.testing.assert_array_equal(
        np.ma.filled(fig_np.axes[3].collections[0].get_array(), 0),
        np.ma.filled(fig_xr.axes[3].collections[0].get_array(), 0),
    )


@pytest.mark.parametrize("case", ["empty_omega", "all_zero", "constant"])
def test_teaser_degenerate_inputs_do_not_raise(case):
    left, right, warped, omega = _fields()
    if case == "empty_omega":
        omega = np.zeros_like(omega)
        text = "no valid pixels"
    elif case == "all_zero":
        left, right, warped = (np.zeros_like(left) for _ in range(3))
        text = "no positive pixel pairs"
    else:
        left, right, warped = (np.full_like(left, 2.5) for _ in range(3))
        text = None
    fig = teaser_figure(left, right, warped, omega)
    ax = fig.axes[3]
    if text is None:
        assert "n/a" in ax.get_title()  # zero variance: rho undefined
        assert np.ma.filled(ax.collections[0].get_array(), 0).sum() == omega.sum()
    else:
        assert [t.get_text() for t in ax.texts] == [text]
    fig.canvas.draw()


def test_teaser_rejects_mismatched_shapes():
    left, right, warped, omega = _fields()
    with pytest.raises(ValueError, match="shape"):
        teaser_figure(left, right[:, :-1], warped, omega)


# --- Fig. 2 -----------------------------------------------------------------------------

SPPS = (128, 256, 512, 1024, 2048)


def _spp_rows():
    rng = np.random.default_rng(0)
    rows = []
    for region, centre in (("all", 0.778), ("non_glass", 0.786), ("glass", 0.38)):
        for spp in SPPS:
            rho = centre + rng.normal(0, 0.003)
            rows.append(
                {
                    "spp": spp,
                    "region": region,
                    "rho": rho,
                    "fisher_low": rho - rng.uniform(0.001, 0.02),
                    "fisher_high": rho + rng.uniform(0.001, 0.02),
                }
            )
    rows[7]["rho"] = math.nan  # non_glass at 512: omitted
    rows[13]["fisher_low"] = math.nan  # glass at 1024: no lower bar
    rng.shuffle(rows)
    return rows


def _containers(fig):
    ax = fig.axes[0]
    return {c.get_label(): c for c in ax.containers}


def test_rho_vs_spp_plots_each_regions_rho_and_ci():
    rows = _spp_rows()
    fig = rho_vs_spp_figure(rows)
    containers = _containers(fig)
    assert len(containers) == len(REGIONS)
    for region in REGIONS:
        label = next(k for k in containers if k.startswith(REGION_LABELS[region] + " ("))
        data_line, _caps, (bars,) = containers[label].lines
        expected = sorted(
            (r for r in rows if r["region"] == region and math.isfinite(r["rho"])),
            key=lambda r: r["spp"],
        )
        x, y = data_line.get_data()
        np.testing.assert_array_equal(x, [r["spp"] for r in expected])
        np.testing.assert_allclose(y, [r["rho"] for r in expected])
        assert data_line.get_marker() not in (None, "None", "")
        segments = bars.get_segments()
        assert len(segments) == len(expected)
        for seg, r in zip(segments, expected, strict=True):
            low = r["fisher_low"] if math.isfinite(r["fisher_low"]) else r["rho"]
            np.testing.assert_allclose(seg[:, 0], r["spp"])
            np.testing.assert_allclose(sorted(seg[:, 1]), [low, r["fisher_high"]])
    non_glass = next(c for k, c in containers.items() if k.startswith("non-glass"))
    assert 512 not in non_glass.lines[0].get_xdata()


def test_rho_vs_spp_legend_reports_relative_variation():
    rows = _spp_rows()
    fig = rho_vs_spp_figure(rows)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert len(labels) == 3
    for region, label in zip(REGIONS, labels, strict=True):
        rho = np.array([r["rho"] for r in rows if r["region"] == region])
        rho = rho[np.isfinite(rho)]
        rel = (rho.max() - rho.min()) / rho.mean()
        assert label.startswith(REGION_LABELS[region])
        assert float(re.search(r"([0-9.]+)%", label).group(1)) == pytest.approx(100 * rel, abs=5e-3)


def test_rho_vs_spp_axis_is_log2_with_ticks_at_the_given_spps():
    fig = rho_vs_spp_figure(_spp_rows(), title="sweep")
    ax = fig.axes[0]
    assert ax.get_xscale() == "log"
    assert ax.xaxis.get_transform().base == 2
    np.testing.assert_array_equal(ax.get_xticks(), SPPS)
    assert [t.get_text() for t in ax.get_xticklabels()] == [str(s) for s in SPPS]
    assert "rho" in ax.get_ylabel()
    assert ax.get_title() == "sweep"


def _boot_rows():
    """Rows of Pearson and the robust statistics, with bootstrap and Fisher-z intervals."""
    rows = []
    for i, region in enumerate(REGIONS):
        for j, method in enumerate(("warp", "spearman", "log", "trimmed")):
            for k, spp in enumerate(SPPS):
                rho = 0.3 + 0.1 * i + 0.02 * j + 0.001 * k
                rows.append(
                    {
                        "spp": spp,
                        "region": region,
                        "method": method,
                        "rho": rho,
                        "boot_low": rho - 0.05 - 0.01 * k,
                        "boot_high": rho + 0.03 + 0.01 * j,
                        "fisher_low": rho - 0.001,
                        "fisher_high": rho + 0.002,
                    }
                )
    # glass, warp, SPP 256: no bootstrap interval, so the Fisher-z one, marked hollow
    fallback = next(
        r for r in rows if (r["region"], r["method"], r["spp"]) == ("glass", "warp", 256)
    )
    fallback["boot_low"] = fallback["boot_high"] = math.nan
    return rows


def test_rho_vs_spp_bars_are_the_bootstrap_interval_with_fisher_only_as_fallback():
    rows = _boot_rows()
    fig = rho_vs_spp_figure(rows)
    ax = fig.axes[0]
    containers = _containers(fig)
    for region in REGIONS:
        label = next(k for k in containers if k.startswith(REGION_LABELS[region] + " ("))
        expected = sorted(
            (r for r in rows if (r["region"], r["method"]) == (region, "warp")),
            key=lambda r: r["spp"],
        )
        data_line, _caps, (bars,) = containers[label].lines
        np.testing.assert_array_equal(data_line.get_xdata(), SPPS)
        np.testing.assert_allclose(data_line.get_ydata(), [r["rho"] for r in expected])
        for seg, r in zip(bars.get_segments(), expected, strict=True):
            if math.isfinite(r["boot_low"]):
                bounds = [r["boot_low"], r["boot_high"]]
            else:
                bounds = [r["fisher_low"], r["fisher_high"]]
            np.testing.assert_allclose(sorted(seg[:, 1]), bounds)
    # the one Fisher-z point is marked with a hollow marker, and the legend says so
    (hollow,) = [ln for ln in ax.get_lines() if ln.get_label() == "_Fisher-z fallback"]
    np.testing.assert_array_equal(hollow.get_xdata(), [256])
    (fallback,) = [r for r in rows if not math.isfinite(r["boot_low"])]
    assert hollow.get_markerfacecolor() == "white"
    assert hollow.get_ydata()[0] == pytest.approx(fallback["rho"])
    title = ax.get_legend().get_title().get_text()
    assert "bootstrap" in title and "Fisher-z" in title


def test_rho_vs_spp_draws_the_robust_statistics_beside_pearson():
    rows = _boot_rows()
    fig = rho_vs_spp_figure(rows)
    ax = fig.axes[0]
    containers = _containers(fig)
    assert len(containers) == 3 * len(REGIONS)  # warp, spearman, log; not trimmed
    for region in REGIONS:
        colour = next(
            c.lines[0].get_color()
            for k, c in containers.items()
            if k.startswith(REGION_LABELS[region] + " (")
        )
        for method, shift, style in (("spearman", 2**0.07, "--"), ("log", 2**-0.07, ":")):
            container = containers[f"{REGION_LABELS[region]}, {method}"]
            expected = sorted(
                (r for r in rows if (r["region"], r["method"]) == (region, method)),
                key=lambda r: r["spp"],
            )
            line = container.lines[0]
            np.testing.assert_allclose(line.get_xdata(), np.array(SPPS) * shift)
            np.testing.assert_allclose(line.get_ydata(), [r["rho"] for r in expected])
            assert line.get_linestyle() == style
            assert line.get_color() == colour
            (bars,) = container.lines[2]
            for seg, r in zip(bars.get_segments(), expected, strict=True):
                np.testing.assert_allclose(sorted(seg[:, 1]), [r["boot_low"], r["boot_high"]])
    # the region legend keeps one entry per region; a second legend names the statistics
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert [label.split(" (")[0] for label in labels] == [REGION_LABELS[r] for r in REGIONS]
    legends = [a for a in ax.get_children() if isinstance(a, Legend)]
    assert len(legends) == 2
    statistics = next(lg for lg in legends if lg is not ax.get_legend())
    assert [t.get_text() for t in statistics.get_texts()] == [
        "Pearson (Eq. 3)",
        "Spearman",
        r"Pearson of $\ln\sigma^2$",
    ]
    fig.canvas.draw()
    # without secondary statistics only Pearson is drawn and there is one legend
    fig = rho_vs_spp_figure(rows, secondary=())
    assert len(_containers(fig)) == len(REGIONS)
    assert sum(isinstance(a, Legend) for a in fig.axes[0].get_children()) == 1


def test_rho_vs_spp_legend_names_fisher_bars_when_there_is_no_bootstrap():
    fig = rho_vs_spp_figure(_spp_rows())
    ax = fig.axes[0]
    title = ax.get_legend().get_title().get_text()
    assert "Fisher-z" in title and "bootstrap 95%" not in title
    # every point falls back, so every point of each region is hollow
    hollow = [ln for ln in ax.get_lines() if ln.get_label() == "_Fisher-z fallback"]
    assert len(hollow) == len(REGIONS)
    for line, container in zip(hollow, _containers(fig).values(), strict=True):
        np.testing.assert_array_equal(line.get_xdata(), container.lines[0].get_xdata())
        np.testing.assert_array_equal(line.get_ydata(), container.lines[0].get_ydata())


def test_rho_vs_spp_degenerate_rows():
    fig = rho_vs_spp_figure([])
    assert [t.get_text() for t in fig.axes[0].texts] == ["no data"]
    rows = [{"spp": 64, "region": "glass", "rho": math.nan, "fisher_low": 0.1, "fisher_high": 0.2}]
    rows.append(
        {"spp": 64, "region": "all", "rho": 0.5, "fisher_low": math.nan, "fisher_high": 0.6}
    )
    fig = rho_vs_spp_figure(rows)
    containers = _containers(fig)
    assert len(containers) == 1
    (label,) = containers
    assert "n/a" not in label and "0.00%" in label
    fig.canvas.draw()
    with pytest.raises(ValueError, match="region"):
        rho_vs_spp_figure([{"spp": 64, "region": "metal", "rho": 0.5}])


# --- Fig. 3 -----------------------------------------------------------------------------


def _material_fields(height=60, width=90, seed=5):
    rng = np.random.default_rng(seed)
    base = np.exp(rng.normal(0.0, 1.5, size=(height, width)))
    left = base * rng.lognormal(0.0, 0.2, size=base.shape)
    warped = base * rng.lognormal(0.0, 0.2, size=base.shape)
    glass = np.zeros((height, width), dtype=bool)
    glass[10:30, 20:50] = True
    warped[glass] = base[glass] * rng.lognormal(0.0, 2.0, size=int(glass.sum()))
    omega = np.ones((height, width), dtype=bool)
    omega[:, :5] = False
    left[40, 60:70] = 0.0
    warped[~omega] = 0.0
    return left, warped, omega, glass


def _scatters(fig):
    cols = [c for c in fig.axes[0].collections if isinstance(c, PathCollection)]
    assert len(cols) == 2
    return cols


@pytest.mark.parametrize("max_points", [50, 400, 10**6])
def test_material_scatter_points_per_group(max_points):
    left, warped, omega, glass = _material_fields()
    fig = material_scatter_figure(left, warped, omega, glass, max_points=max_points)
    non_glass_pts, glass_pts = _scatters(fig)
    pos = omega & (left > 0) & (warped > 0)
    for col, region in ((non_glass_pts, pos & ~glass), (glass_pts, pos & glass)):
        offsets = col.get_offsets()
        assert len(offsets) == min(int(region.sum()), max_points)
        # every plotted point is a real pixel pair of its group
        pairs = {(a, b) for a, b in zip(left[region], warped[region], strict=True)}
        assert all((a, b) in pairs for a, b in np.asarray(offsets))
    np.testing.assert_allclose(non_glass_pts.get_facecolor()[0][:3], to_rgba(NON_GLASS_COLOUR)[:3])
    np.testing.assert_allclose(glass_pts.get_facecolor()[0][:3], to_rgba(GLASS_COLOUR)[:3])
    assert glass_pts.get_zorder() > non_glass_pts.get_zorder()
    ax = fig.axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    diag = [ln for ln in ax.get_lines() if ln.get_label() == "$y = x$"]
    assert len(diag) == 1
    np.testing.assert_allclose(*diag[0].get_data())


def test_material_scatter_subsample_is_deterministic():
    left, warped, omega, glass = _material_fields()

    def offsets(seed):
        fig = material_scatter_figure(left, warped, omega, glass, max_points=100, seed=seed)
        out = [np.asarray(c.get_offsets()).copy() for c in _scatters(fig)]
        plt.close(fig)
        return out

    a, b, c = offsets(7), offsets(7), offsets(8)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)
    assert not np.array_equal(a[0], c[0])


def test_material_scatter_legend_rho_matches_corrcoef():
    left, warped, omega, glass = _material_fields()
    fig = material_scatter_figure(left, warped, omega, glass, max_points=100, title="scene 3")
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels[0].startswith("non-glass") and labels[1].startswith("glass")
    for label, region in ((labels[0], omega & ~glass), (labels[1], omega & glass)):
        assert _rho_in(label) == pytest.approx(_corr(left[region], warped[region]), abs=5e-5)
        assert f"n = {int(region.sum())}" in label
    assert _rho_in(labels[0]) > _rho_in(labels[1])
    assert fig.axes[0].get_title() == "scene 3"


@pytest.mark.parametrize("case", ["no_glass", "empty_omega", "all_zero", "all_glass"])
def test_material_scatter_degenerate_inputs_do_not_raise(case):
    left, warped, omega, glass = _material_fields()
    if case == "no_glass":
        glass = np.zeros_like(glass)
    elif case == "empty_omega":
        omega = np.zeros_like(omega)
    elif case == "all_zero":
        left = np.zeros_like(left)
    else:
        glass = np.ones_like(glass)
    fig = material_scatter_figure(
        xr.DataArray(left, dims=("y", "x")), warped, omega, xr.DataArray(glass, dims=("y", "x"))
    )
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    if case in ("no_glass", "empty_omega"):
        assert labels[1] == "glass: no pixels"
    if case in ("all_glass", "empty_omega"):
        assert labels[0] == "non-glass: no pixels"
    if case == "all_zero":
        assert all(len(c.get_offsets()) == 0 for c in _scatters(fig))
        assert "n/a" in labels[0]
    fig.canvas.draw()


def test_material_scatter_rejects_bad_options():
    left, warped, omega, glass = _material_fields()
    with pytest.raises(ValueError, match="max_points"):
        material_scatter_figure(left, warped, omega, glass, max_points=0)
    with pytest.raises(ValueError, match="shape"):
        material_scatter_figure(left, warped, omega, glass[:-1])


def _margin_rows(rng):
    rows = []
    for cost in ("residual_sad", "variance_cost"):
        for condition, shift in (("normal", 1.0), ("decorrelated", -1.0)):
            for value in rng.normal(shift, 1.0, size=300):
                rows.append(
                    {"cost": cost, "region": "non_glass", "condition": condition, "margin": value}
                )
    rows.append({"cost": "residual_sad", "region": "glass", "condition": "normal", "margin": "nan"})
    return rows


def test_margin_figure_legends_give_median_and_share_won_by_the_ground_truth():
    from stereovar.figures.margins import margin_distribution_figure

    rows = _margin_rows(np.random.default_rng(0))
    fig = margin_distribution_figure(rows, title="t")
    axes = fig.axes
    assert len(axes) == 4
    non_glass = axes[0]  # (residual SAD, non-glass)
    labels = [t.get_text() for t in non_glass.get_legend().get_texts()]
    for condition, label in zip(("normal", "decorrelated"), labels, strict=True):
        values = np.array(
            [
                r["margin"]
                for r in rows
                if (r["cost"], r["region"], r["condition"])
                == ("residual_sad", "non_glass", condition)
            ]
        )
        assert label.startswith(condition)
        assert f"median {np.median(values):.3g}" in label
        assert f"P(m>0) {np.mean(values > 0):.1%}" in label
        assert f"n={values.size}" in label
    # Each histogram gives the share of its margins per bin, over bins spanning all of them.
    pooled = np.array(
        [r["margin"] for r in rows if (r["cost"], r["region"]) == ("residual_sad", "non_glass")]
    )
    for patch in non_glass.patches:
        xy = patch.get_xy()
        edges = np.unique(xy[:, 0])  # a step outline: (e0, 0), (e0, h0), (e1, h0), (e1, h1)...
        heights = xy[1 : 2 * edges.size - 2 : 2, 1]
        assert heights.sum() == pytest.approx(1.0, rel=1e-9)
        assert (edges[0], edges[-1]) == pytest.approx((pooled.min(), pooled.max()), rel=1e-9)
    assert non_glass.get_xscale() == "symlog"
    # The glass column has no finite margin (the one NaN row is dropped).
    assert any("no scored pixels" in t.get_text() for t in axes[1].texts)


def test_margin_figure_rejects_bad_bins():
    from stereovar.figures.margins import margin_distribution_figure

    with pytest.raises(ValueError, match="bins"):
        margin_distribution_figure([], bins=0)


def test_margin_figure_draws_a_single_repeated_value():
    from stereovar.figures.margins import margin_distribution_figure

    rows = [
        {"cost": "variance_cost", "region": "glass", "condition": c, "margin": 2.0}
        for c in ("normal", "decorrelated")
    ]
    ax = margin_distribution_figure(rows).axes[3]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert all("median 2," in label and "P(m>0) 100.0%" in label for label in labels)
    assert all(patch.get_xy()[:, 1].max() == pytest.approx(1.0) for patch in ax.patches)
