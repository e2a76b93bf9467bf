"""Every figure of ``stereovar.figures`` is laid out cleanly: no text cut off at the figure's
edge and no two texts drawn over each other (:func:`stereovar.figures.layout.layout_problems`),
on synthetic inputs of the shapes the workflow gives, small and large (many scenes, long
mitigation and renderer names, wide value ranges); and the check itself finds what it should.

Set ``STEREOVAR_FIGURE_DIR`` to save every figure as PNG there for a look.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402

from stereovar.figures.layout import layout_problems, overlap_depth, wrap_to_width  # noqa: E402

DPI = 100
"""About the dpi the jobs save at (90-120): text extents are rounded to whole pixels, so a
figure drawn much coarser can hide an overhang of a point or two."""

SIZES = ("small", "large")

AUDIT_TITLE = "f00, N = 4 (renderer audit/mitsuba-seeds-png-scene-000, estimator seeds)"


# ---------------------------------------------------------------- the check on built figures


def _fig(**kw):
    return plt.figure(figsize=kw.pop("figsize", (4, 3)), dpi=DPI, **kw)


def test_clean_figure_has_no_problems():
    fig, ax = plt.subplots(figsize=(4, 3), dpi=DPI, layout="constrained")
    ax.plot([0, 1], [0, 1], label="line")
    ax.set_title("a title that fits")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.legend(loc="lower right")
    assert layout_problems(fig) == []
    plt.close(fig)


def test_title_past_the_edge_is_clipped():
    fig, ax = plt.subplots(figsize=(3, 2), dpi=DPI)
    ax.set_title("a title much too long for a figure three inches wide, by far")
    problems = layout_problems(fig)
    plt.close(fig)
    assert any(p.startswith("clipped: title") and "left" in p and "right" in p for p in problems)


def test_text_below_the_figure_is_clipped():
    fig = _fig()
    fig.text(0.5, -0.05, "under the bottom edge", ha="center", va="top")
    problems = layout_problems(fig)
    plt.close(fig)
    assert problems and "bottom" in problems[0]


def test_two_overlapping_labels_collide_and_apart_do_not():
    fig, ax = plt.subplots(figsize=(4, 3), dpi=DPI)
    ax.annotate("denoise_sensor", (0.5, 0.5))
    ax.annotate("denoise", (0.52, 0.5))
    ax.annotate("far away", (0.1, 0.1))
    problems = layout_problems(fig)
    plt.close(fig)
    assert len(problems) == 1
    assert "'denoise_sensor'" in problems[0] and "'denoise'" in problems[0]
    assert problems[0].startswith("colliding:")


def test_dense_tick_labels_collide():
    fig, ax = plt.subplots(figsize=(2, 2), dpi=DPI, layout="constrained")
    ax.set_xticks(range(20), [f"label {k}" for k in range(20)])
    problems = layout_problems(fig)
    plt.close(fig)
    assert any("x tick label" in p and p.startswith("colliding") for p in problems)


def test_rotated_neighbours_compare_by_their_rotated_rectangles():
    """At 45 degrees the axis-aligned boxes of two neighbours overlap while the glyphs do not;
    at 0 degrees the same labels at the same spots collide."""
    labels = ["rotated one", "rotated two"]
    fig, ax = plt.subplots(figsize=(4, 3), dpi=DPI, layout="constrained")
    ax.set_xticks([0, 0.12], labels, rotation=45, ha="right", rotation_mode="anchor")
    ax.set_xlim(-0.5, 0.6)
    renderer = (fig.canvas.draw(), fig.canvas.get_renderer())[1]
    boxes = [t.get_window_extent(renderer) for t in ax.get_xticklabels()]
    assert boxes[0].overlaps(boxes[1])  # the axis-aligned boxes overlap ...
    assert layout_problems(fig) == []  # ... the rotated rectangles do not
    for t in ax.get_xticklabels():
        t.set_rotation(0)
    assert any(p.startswith("colliding") for p in layout_problems(fig))
    plt.close(fig)


def test_legend_frame_covering_a_text_collides():
    fig, ax = plt.subplots(figsize=(4, 3), dpi=DPI)
    for k in range(6):
        ax.plot([0, 1], [k, k], label=f"series {k}")
    ax.legend(loc="center")
    ax.text(0.5, 0.5, "under the legend", transform=ax.transAxes, ha="center")
    problems = layout_problems(fig)
    plt.close(fig)
    assert any("legend frame" in p and "under the legend" in p for p in problems)


def test_overlap_depth_of_rotated_squares():
    """A square turned 45 degrees about its centre, moved along x: apart once its corner
    (at distance sqrt(2)/2 from its centre) clears the other square's edge at 1/2."""
    unit = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    c = s = math.sqrt(0.5)
    turned = unit @ np.array([[c, -s], [s, c]]).T
    reach = 0.5 + math.sqrt(0.5)
    assert overlap_depth(unit, turned + [reach - 0.1, 0.0]) == pytest.approx(0.1, abs=1e-12)
    assert overlap_depth(unit, turned + [reach + 0.1, 0.0]) < 0


def test_wrap_to_width_keeps_words_and_line_breaks():
    text = "every statistic and control, 20 scenes\nrenderer mitsuba, estimator seeds"
    wrapped = wrap_to_width(text, 2.0, fontsize=12)
    assert wrapped.replace("\n", " ").split() == text.replace("\n", " ").split()
    assert max(len(line) for line in wrapped.split("\n")) <= 2.0 * 72 / (0.6 * 12)


# ---------------------------------------------------------------- synthetic inputs


def _rng(size):
    return np.random.default_rng(0 if size == "small" else 1)


def _fields(size):
    """sigma_L^2, sigma_R^2, warped, omega, glass of an (H, W) frame, heavy-tailed."""
    h, w = (36, 64) if size == "small" else (72, 128)
    rng = _rng(size)
    base = np.exp(rng.normal(-6.0, 2.0, (h, w)))
    left = base * np.exp(rng.normal(0, 0.3, (h, w)))
    right = base * np.exp(rng.normal(0, 0.3, (h, w)))
    warped = right * np.exp(rng.normal(0, 0.2, (h, w)))
    omega = np.ones((h, w), bool)
    omega[:, : w // 10] = False
    glass = np.zeros((h, w), bool)
    glass[h // 3 : h // 2, w // 2 : 3 * w // 4] = True
    return left, right, warped, omega, glass


REGIONS = ("all", "non_glass", "glass")
STATISTICS = ("warp", "spearman", "log", "trimmed")
CONTROLS = ("no_warp", "null_shift", "null_flip", "partial", "relative", "sensor", "sensor_sim")


def _correlation_rows(size, *, audit=False, spps=None):
    rng = _rng(size)
    scenes = ["f00"] if audit else [f"scene_{k:03d}" for k in range(1 if size == "small" else 20)]
    spps = spps or ([32] if size == "small" else [32, 64, 128, 256, 512, 1024, 2048])
    rows = []
    for scene in scenes:
        for spp in spps:
            for region in REGIONS:
                for method in (*STATISTICS, *CONTROLS):
                    empty = audit and region != "all"
                    rho = math.nan if empty else float(rng.uniform(-0.2, 0.99))
                    half = float(rng.uniform(0.01, 0.2))
                    rows.append({
                        "scene": scene, "spp": 0 if audit else spp, "region": region,
                        "method": method, "rho": rho,
                        "boot_low": rho - half, "boot_high": min(rho + half, 1.0),
                        "fisher_low": rho - half / 5, "fisher_high": rho + half / 5,
                        "renderer": "mitsuba", "estimator": "seeds",
                    })  # fmt: skip
    return rows


def _seed_curve_rows(size, *, audit=False):
    n_primes = [2, 4] if size == "small" or audit else [2, 4, 8, 16, 32, 64]
    rows = []
    for region in REGIONS:
        for method in ("warp", "log"):
            for n in n_primes:
                empty = audit and region != "all"
                rho = math.nan if empty else 0.3 + 0.4 * (1 - 1 / n)
                rows.append({
                    "region": region, "method": method, "n_prime": n, "mean_rho": rho,
                    "std_rho": 0.05, "mean_rho_corrected": math.nan if empty else 0.8,
                    "n_scenes": 1 if audit or size == "small" else 20,
                })  # fmt: skip
    return rows


def _margin_rows(size):
    """Heavy-tailed GT margins with a small median |m| (so the symlog axis has ticks on both
    sides of 0 near each other)."""
    rng = _rng(size)
    n = 400 if size == "small" else 4000
    rows = []
    for cost, scale in (("residual_sad", 0.1), ("variance_cost", 0.003)):
        for region in ("non_glass", "glass"):
            for condition in ("normal", "decorrelated"):
                m = -scale * np.exp(rng.normal(0, 2.0, n)) * rng.choice([1, 1, 1, -1], n)
                rows += [
                    {"cost": cost, "region": region, "condition": condition, "margin": float(v)}
                    for v in m
                ]
    return rows


MITIGATIONS = (
    "none", "shared_seed", "spp_x4", "denoise", "denoise_sensor", "equalise", "sensor_only",
)  # fmt: skip
LONG_MITIGATIONS = (
    *MITIGATIONS, "equalise|shipped", "sensor_only|shipped", "denoise_then_equalise_strong",
)  # fmt: skip


def _mitigation_rows(size):
    """Points as the default run gives them: several mitigations at nearly one spot."""
    names = MITIGATIONS if size == "small" else LONG_MITIGATIONS
    psnr = {"none": 19.5, "shared_seed": 19.4, "spp_x4": 25.6, "denoise": 23.6,
            "denoise_sensor": 23.3, "equalise": 27.9, "sensor_only": 27.9}  # fmt: skip
    rows = []
    for k, name in enumerate(names):
        for region in REGIONS:
            row = {"mitigation": name, "region": region}
            for column, value in (
                ("psnr", psnr.get(name, 24.0 + 0.1 * k)),
                ("partial", 0.56 + 0.01 * (k % 3) if k < 5 else 0.0),
                ("cs_lift", 0.2 + 0.03 * (k % 4)),
                ("residual_rho_zero", 0.6 if name == "shared_seed" else 0.0),
            ):
                row.update({column: value, f"{column}_low": value - 0.05,
                            f"{column}_high": value + 0.05})  # fmt: skip
            row["psnr_low"], row["psnr_high"] = row["psnr"] - 3.5, row["psnr"] + 3.5
            rows.append(row)
    return rows


def _calibration_rows(size):
    transforms = ["none", "denoise"] if size == "small" else [
        "none", "denoise", "denoise_sensor", "equalise", "equalise|shipped", "sensor_only",
        "sensor_only|shipped",
    ]  # fmt: skip
    rows = []
    for k, transform in enumerate(transforms):
        for factor in (0.0625, 0.125, 0.25, 1.0, 2.0):
            p = min(1.0, factor * (2 + k))
            rows.append({"check": "power", "rule": "above_null", "scope": "combined",
                         "transform": transform, "method": "partial", "kind": "planted",
                         "strength_factor": factor, "value": p, "low": max(p - 0.2, 0.0),
                         "high": min(p + 0.1, 1.0)})  # fmt: skip
        for rule in ("above_zero", "above_null"):
            for kind in ("camera", "misaligned"):
                v = 0.9 if rule == "above_zero" and k % 2 else 0.02
                rows.append({"check": "false_positive_rate", "rule": rule, "scope": "combined",
                             "transform": transform, "method": "partial", "kind": kind,
                             "strength_factor": 0.0, "value": v, "low": max(v - 0.05, 0.0),
                             "high": min(v + 0.2, 1.0)})  # fmt: skip
    return rows


def _probe_rows(size):
    from stereovar.probe.inputs import TEST_INPUTS

    architectures = ["mccnn"] if size == "small" else ["mccnn", "costvolume"]
    tested = ["none", "planted_x1", "sensor_only"]
    if size == "large":
        tested += ["planted_x0.25", "planted_x0.5", "planted_x2"]
    rows = []
    for arch in architectures:
        for condition in tested:
            for test_input in TEST_INPUTS:
                for region in ("all", "non_glass"):
                    acc = 0.8 + 0.02 * len(condition) % 0.1
                    did = 0.005 if condition == "none" else 0.02
                    rows.append({
                        "architecture": arch, "tested": condition, "test_input": test_input,
                        "region": region, "accuracy": acc, "accuracy_low": acc - 0.01,
                        "accuracy_high": acc + 0.01, "twin_accuracy": acc - 0.01,
                        "twin_accuracy_low": acc - 0.02, "twin_accuracy_high": acc,
                        "did": did, "did_low": did - 0.003, "did_high": did + 0.003,
                        "did_mde": 0.0034,
                    })  # fmt: skip
    return rows


def _generator_rows(size):
    profiles = ["paper", "cycles_default"] if size == "small" else [
        "paper", "cycles_default", "cycles_adaptive_denoised", "blenderproc_defaults",
        "kubric_like_shared_seed", "infinigen_like",
    ]  # fmt: skip
    rows = []
    for k, profile in enumerate(profiles):
        for region in ("all", "non_glass"):
            row = {"profile": profile, "region": region, "generator_spp": 1024 if k else 64,
                   "spp": 64, "null_partial": 0.006 if k % 2 else math.nan}  # fmt: skip
            for column, value in (("mc_specific", 0.46 - 0.05 * k), ("residual_rho_zero", 0.0),
                                  ("psnr", 25.0 + k)):  # fmt: skip
                row.update({column: value, f"{column}_low": value - 0.07,
                            f"{column}_high": value + 0.07})  # fmt: skip
            rows.append(row)
    return rows


def _estimator_rows(size):
    scenes = ["scene_000"] if size == "small" else [f"scene_{k:03d}" for k in range(6)]
    fields = []
    for scene in scenes:
        for view in ("left", "right"):
            fields.append({"scene": scene, "view": view, "spearman": 0.8, "pearson": 0.7,
                           "reference_reliability_spearman": 0.85,
                           "reference_reliability_pearson": 0.75, "mean_ratio": 1.01,
                           "ratio_low": 0.95, "ratio_high": 1.07})  # fmt: skip
    stats = []
    for scene in scenes:
        for method in (*STATISTICS, *CONTROLS):
            stats.append({"scene": scene, "region": "all", "method": method,
                          "seeds_rho": 0.5, "seeds_corrected": 0.7, "moments_rho": 0.45,
                          "moments_corrected": 0.65})  # fmt: skip
    return fields, stats


def _ground_truth(size, *, masked=True):
    h, w = (36, 64) if size == "small" else (72, 128)
    rng = _rng(size)
    material = rng.integers(0, 6, (2, h, w))
    disparity = rng.uniform(1, 30, (2, h, w))
    return xr.Dataset(
        {
            "disparity": (("view", "y", "x"), disparity),
            "valid": (("view", "y", "x"), disparity > 3),
            "material": (("view", "y", "x"), material),
            "glass": (("view", "y", "x"), material == 4),
        },
        coords={"view": ["left", "right"]},
        attrs={"disparity_sign": 1, "material_mask": "glass" if masked else "none"},
    )


def _render(size):
    h, w = (36, 64) if size == "small" else (72, 128)
    return _rng(size).uniform(0, 1, (h, w, 3))


# ---------------------------------------------------------------- every figure


def _teaser(size):
    from stereovar.figures.teaser import teaser_figure

    left, right, warped, omega, _ = _fields(size)
    return teaser_figure(left, right, warped, omega, title=AUDIT_TITLE, bins=20)


def _rho_vs_spp(size):
    from stereovar.figures.rho_vs_spp import rho_vs_spp_figure

    title = "scene_000: rho against SPP (renderer mitsuba, estimator seeds)"
    rows = [r for r in _correlation_rows("small", spps=[32] if size == "small" else
            [32, 64, 128, 256, 512, 1024, 2048]) if r["method"] in STATISTICS]  # fmt: skip
    return rho_vs_spp_figure(rows, title=title)


def _material_scatter(size):
    from stereovar.figures.material_scatter import material_scatter_figure

    left, _, warped, omega, glass = _fields(size)
    title = "scene_000, SPP 32 (renderer mitsuba, estimator seeds)"
    if size == "large":
        title = "scene_with_a_long_name_017, SPP 2048 (renderer cycles, estimator moments)"
    return material_scatter_figure(left, warped, omega, glass, title=title, max_points=500)


def _margins(size):
    from stereovar.figures.margins import margin_distribution_figure

    title = "GT margins, normal vs decorrelated (4 scenes, sampled pixels)"
    title += "\nrenderer mitsuba, estimator seeds"
    return margin_distribution_figure(_margin_rows(size), title=title, bins=30)


def _rho_vs_seeds(size):
    from stereovar.figures.uncertainty import rho_vs_seeds_figure

    title = "rho against seeds N' (renderer mitsuba, estimator seeds)"
    return rho_vs_seeds_figure(_seed_curve_rows(size), title=title)


def _rho_vs_seeds_audit(size):
    from stereovar.figures.uncertainty import rho_vs_seeds_figure

    title = "rho against seeds N' (renderer audit/synthetic, estimator seeds)"
    return rho_vs_seeds_figure(_seed_curve_rows(size, audit=True), title=title, drop_empty=True)


def _statistics_dots(size):
    from stereovar.figures.uncertainty import statistics_dot_figure

    n = 1 if size == "small" else 20
    title = f"every statistic and control, {n} scenes, SPP 32"
    title += " (renderer mitsuba, estimator seeds)"
    return statistics_dot_figure(_correlation_rows(size, spps=[32]), spp=32, title=title)


def _statistics_dots_audit(size):
    from stereovar.figures.uncertainty import statistics_dot_figure

    title = "every statistic and control, 1 scene (renderer audit/synthetic, estimator seeds)"
    rows = _correlation_rows(size, audit=True)
    return statistics_dot_figure(rows, title=title, drop_empty=True)


def _estimators(size):
    from stereovar.figures.estimators import estimator_figure

    return estimator_figure(*_estimator_rows(size))


def _cross_renderer(size):
    from stereovar.figures.cross_renderer import cross_renderer_figure

    renderers = ["mitsuba", "cycles"] if size == "small" else ["mitsuba", "cycles", "pbrt"]
    left, right, *_ = _fields(size)
    fields = {r: (left, right) for r in renderers}
    rho = {r: (0.5, 0.4, 0.6) for r in renderers}
    title = "scene_000, SPP 32: sigma^2 by renderer"
    return cross_renderer_figure(fields, rho=rho, title=title)


def _mitigations(size):
    from stereovar.figures.mitigations import tradeoff_figure

    return tradeoff_figure(_mitigation_rows(size))


def _calibration(size):
    from stereovar.figures.calibration import calibration_figure

    return calibration_figure(_calibration_rows(size))


def _probe(size):
    from stereovar.figures.probe import probe_figure

    return probe_figure(_probe_rows(size))


def _generators(size):
    from stereovar.figures.generators import generators_figure

    return generators_figure(_generator_rows(size))


def _preview(size):
    from stereovar.figures.preview import preview_figure

    render = _render(size)
    return preview_figure(render, render, _ground_truth(size), title="scene_000 (mitsuba)", spp=16)


def _thumbnail(size):
    from stereovar.figures.preview import thumbnail_figure

    # the audit's title: the frame and the last three parts of its first file's path
    title = (
        "frame_000123: kitchen_sequence_2024-05-01_mitsuba/left_camera/"
        "frame_000123_seed_0000_radiance.exr"
    )
    return thumbnail_figure(_render(size), _ground_truth(size, masked=size == "large"),
                            title=title)  # fmt: skip


def _strongest(size):
    strongest = pytest.importorskip("stereovar.figures.strongest")
    h, w = (36, 64) if size == "small" else (72, 128)
    tile = 8
    frames = []
    for k in range(1 if size == "small" else 3):
        rng = np.random.default_rng(k)
        rows = [{"rank": r + 1, "x0": 8 * (2 * r), "y0": 8, "x1": 8 * (2 * r + 1), "y1": 16,
                 "stands_out": r == 0} for r in range(3)]  # fmt: skip
        frames.append({
            "frame": f"frame_{k:06d}", "image": rng.uniform(0, 1, (h, w, 3)),
            "rho": rng.uniform(-1, 1, (h // tile, w // tile)), "rows": rows,
            "e_left": rng.normal(size=(h, w)), "e_right": rng.normal(size=(h, w)),
        })  # fmt: skip
    return strongest.strongest_figure(frames, tile=tile)


FIGURES = {
    "teaser": _teaser,
    "rho_vs_spp": _rho_vs_spp,
    "material_scatter": _material_scatter,
    "margins": _margins,
    "rho_vs_seeds": _rho_vs_seeds,
    "rho_vs_seeds_audit": _rho_vs_seeds_audit,
    "statistics_dots": _statistics_dots,
    "statistics_dots_audit": _statistics_dots_audit,
    "estimators": _estimators,
    "cross_renderer": _cross_renderer,
    "mitigations": _mitigations,
    "calibration": _calibration,
    "probe": _probe,
    "generators": _generators,
    "preview": _preview,
    "thumbnail": _thumbnail,
    "strongest": _strongest,
}

ONE_SIZE = {"teaser", "margins", "rho_vs_seeds_audit", "statistics_dots_audit", "preview"}
"""Figures whose layout does not change with the input's size (one panel grid, one title):
drawn once, small."""

CASES = [(n, s) for n in sorted(FIGURES) for s in SIZES if s == "small" or n not in ONE_SIZE]


def test_every_figure_function_is_built_here():
    """A new figure function must be added to FIGURES (and named here)."""
    import importlib
    import inspect
    import pkgutil

    import stereovar.figures as package

    found = set()
    for info in pkgutil.iter_modules(package.__path__):
        module = importlib.import_module(f"stereovar.figures.{info.name}")
        for name, fn in inspect.getmembers(module, inspect.isfunction):
            if fn.__module__ == module.__name__ and name.endswith("_figure"):
                found.add(name)
    built = {
        "teaser_figure", "rho_vs_spp_figure", "material_scatter_figure",
        "margin_distribution_figure", "rho_vs_seeds_figure", "statistics_dot_figure",
        "estimator_figure", "cross_renderer_figure", "tradeoff_figure", "calibration_figure",
        "probe_figure", "generators_figure", "preview_figure", "thumbnail_figure",
        "strongest_figure",
    }  # fmt: skip
    assert found <= built


@pytest.mark.parametrize(("name", "size"), CASES)
def test_figure_layout_is_clean(name, size):
    with matplotlib.rc_context({"figure.dpi": DPI}):
        fig = FIGURES[name](size)
        problems = layout_problems(fig)
    out = os.environ.get("STEREOVAR_FIGURE_DIR")
    if out:
        Path(out).mkdir(parents=True, exist_ok=True)
        fig.savefig(Path(out) / f"{name}_{size}.png", dpi=80)
    plt.close(fig)
    assert problems == []


# ---------------------------------------------------------------- the jobs' titles and panels


@pytest.fixture
def saved(monkeypatch):
    """The figures the figure jobs save, kept open (the jobs' ``_save`` replaced)."""
    import stereovar.jobs.figures as jobs

    figures = []
    monkeypatch.setattr(jobs, "_save", lambda fig, out: figures.append(fig))
    yield figures
    for fig in figures:
        plt.close(fig)


def _csv(path, rows):
    from stereovar.io.tables import to_csv

    columns = list(dict.fromkeys(k for r in rows for k in r))
    path.write_text(to_csv(rows, columns))
    return str(path)


def _panel_texts(fig):
    return [t.get_text() for ax in fig.axes for t in ax.texts]


def test_audit_statistics_dots_show_only_the_regions_with_data(tmp_path, saved):
    """An audit without a material mask has rows for glass and non-glass with no pixels
    (rho NaN): its figure has the one panel with data, and no SPP in its title."""
    from stereovar.jobs.figures import statistics_dot_figure_job

    rows = _correlation_rows("small", audit=True)
    for r in rows:
        r["renderer"] = "audit/synthetic"
    statistics_dot_figure_job([_csv(tmp_path / "spp0.csv", rows)], tmp_path / "o.png", spp=0)
    (fig,) = saved
    assert [ax.get_title() for ax in fig.axes] == ["all pixels"]
    assert "no data" not in _panel_texts(fig)
    title = fig.get_suptitle()
    assert "SPP" not in title and "1 frame " in title.replace("\n", " ") + " "
    assert "audit " in title and "renderer" not in title  # the audit by name, not a renderer
    assert layout_problems(fig) == []


def test_statistics_dots_of_a_run_keep_every_region_and_say_its_spp(tmp_path, saved):
    from stereovar.jobs.figures import statistics_dot_figure_job

    rows = _correlation_rows("small", spps=[32])
    statistics_dot_figure_job([_csv(tmp_path / "spp32.csv", rows)], tmp_path / "o.png", spp=32)
    (fig,) = saved
    assert [ax.get_title() for ax in fig.axes] == ["all pixels", "non-glass", "glass"]
    assert "SPP 32" in fig.get_suptitle()


def test_audit_rho_vs_seeds_shows_only_the_regions_with_data(tmp_path, saved):
    from stereovar.jobs.figures import rho_vs_seeds_figure_job

    rows = [{**r, "renderer": "audit/synthetic", "estimator": "seeds"}
            for r in _seed_curve_rows("small", audit=True)]  # fmt: skip
    rho_vs_seeds_figure_job(_csv(tmp_path / "curve.csv", rows), tmp_path / "o.png")
    (fig,) = saved
    assert [ax.get_title() for ax in fig.axes] == ["all pixels (1 scene)"]
    assert "no data" not in _panel_texts(fig)


def _variance_store(spp):
    left, right, warped, omega, _ = _fields("small")
    attrs = {"scene": "f00", "spp": spp, "renderer": "audit/synthetic", "estimator": "seeds",
             "n_seeds": 4}  # fmt: skip
    v = xr.Dataset({"variance": (("view", "y", "x"), np.stack([left, right]))},
                   coords={"view": ["left", "right"]}, attrs=attrs)  # fmt: skip
    w = xr.Dataset({"warped_variance": (("y", "x"), warped), "omega": (("y", "x"), omega)},
                   attrs=attrs)  # fmt: skip
    return v, w


def test_teaser_title_of_an_audit_says_no_spp(monkeypatch, saved):
    """Audit renders carry SPP 0 (not given): the title says nothing of it (the title of a
    known SPP: the doctest of ``stereovar.jobs.figures._spp``)."""
    import stereovar.io.store as store
    from stereovar.jobs.figures import teaser_figure_job

    v, w = _variance_store(0)
    monkeypatch.setattr(store, "load_store", lambda path, what, *a, **k: v if "var" in path else w)
    with matplotlib.rc_context({"figure.dpi": DPI}):
        teaser_figure_job("variance.nc", "warped.nc", "out.png")
    (fig,) = saved
    title = fig.get_suptitle()
    assert "SPP" not in title
    assert title.startswith("f00, N = 4")


def test_figure_job_logs_what_the_check_finds(tmp_path, caplog):
    """The jobs' save logs one warning per problem, and the PNG is written all the same."""
    import logging

    from stereovar.jobs.figures import _save

    fig, ax = plt.subplots(figsize=(3, 2), layout="constrained")
    ax.set_title("a title much too long for a figure three inches wide, by far")
    with caplog.at_level(logging.WARNING):
        _save(fig, tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 0
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1 and "clipped: title" in warnings[0]
