"""The Cycles renderer (render.renderer: cycles) against the renderer-neutral ground truth and
against Mitsuba, at tiny sizes.

bpy wheels exist for CPython 3.11 only: on 3.11 these tests run (``make test`` installs the
``cycles`` extra) and a missing bpy fails them; on other versions the module is skipped.
"""

import sys

import numpy as np
import pytest

if sys.version_info[:2] != (3, 11):
    pytest.skip("bpy wheels exist for CPython 3.11 only", allow_module_level=True)

import bpy  # noqa: E402,F401  (a missing cycles extra fails here on 3.11)

from stereovar.audit.sign import median_relative_error  # noqa: E402
from stereovar.config import validate_config  # noqa: E402
from stereovar.errors import BackendError, ConfigError  # noqa: E402
from stereovar.ground_truth import compute_ground_truth  # noqa: E402
from stereovar.renderers import get_renderer  # noqa: E402
from stereovar.renderers.base import RenderSettings  # noqa: E402
from stereovar.renderers.cycles.settings import bounces, cycles_seed  # noqa: E402
from stereovar.seeding import render_seed  # noqa: E402
from stereovar.statistics.warp import warp_right_to_left  # noqa: E402

from .test_photometric import lambertian_spec  # noqa: E402

SCHEMA = "workflow/schemas/config.schema.yaml"
WIDTH, HEIGHT, BASELINE = 64, 36, 0.08
SETTINGS = RenderSettings(max_depth=4)


def prepare(renderer, convention="paper", width=WIDTH, height=HEIGHT):
    rig = {"width": width, "height": height, "baseline_m": BASELINE, "convention": convention}
    return get_renderer(renderer).prepare(lambertian_spec(), rig=rig, threads=2)


@pytest.fixture(scope="module")
def cycles_scene():
    return prepare("cycles")


def test_missing_bpy_is_one_line_naming_the_extra(monkeypatch):
    from stereovar.renderers.cycles.backend import load_bpy

    monkeypatch.setitem(sys.modules, "bpy", None)
    with pytest.raises(BackendError) as err:
        load_bpy()
    message = str(err.value)
    assert "\n" not in message and ".[cycles]" in message and "render.renderer" in message


@pytest.mark.parametrize(
    "cycles, key",
    [
        ({"denoise": True}, "render.cycles.denoise"),
        ({"adaptive_sampling": True}, "render.cycles.adaptive_sampling"),
        ({"view_transform": "Filmic"}, "render.cycles.view_transform"),
        ({"view_transform": "AgX"}, "render.cycles.view_transform"),
    ],
)
def test_settings_that_change_the_variance_are_refused(cycles, key):
    config = {"render": {"renderer": "cycles", "cycles": cycles}}
    with pytest.raises(ConfigError) as err:
        validate_config(config, SCHEMA)
    message = str(err.value)
    assert "\n" not in message and key in message and "refused" in message
    # the same settings under Mitsuba are not read, so not refused
    validate_config({"render": {"renderer": "mitsuba", "cycles": cycles}}, SCHEMA)


def test_a_path_depth_cycles_cannot_express_is_refused():
    with pytest.raises(ConfigError, match="render.max_depth.*use 2 or more"):
        validate_config({"render": {"renderer": "cycles", "max_depth": 1}}, SCHEMA)


def test_the_moments_estimator_is_refused_for_cycles():
    for config in (
        {"render": {"renderer": "cycles", "estimator": "moments"}},
        {"renderers": ["mitsuba", "cycles"], "render": {"estimator": "moments"}},
    ):
        with pytest.raises(ConfigError, match="render.estimator.*set render.estimator: seeds"):
            validate_config(config, SCHEMA)


@pytest.mark.parametrize("metal", ["Cu", "Al", "Au"])
def test_conductor_colour_is_the_normal_incidence_fresnel_reflectance(mi, metal):
    """The Principled base colour of a conductor against the conductor Fresnel equation at
    normal incidence, :math:`F_0 = ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2)`, with Mitsuba's
    own eta and k of that metal."""
    from stereovar.renderers.cycles.scene import conductor_rgb

    params = mi.traverse(mi.load_dict({"type": "conductor", "material": metal}))
    n = np.asarray(params["eta.value"], dtype=np.float64).reshape(-1)[:3]
    k = np.asarray(params["k.value"], dtype=np.float64).reshape(-1)[:3]
    expected = ((n - 1) ** 2 + k**2) / ((n + 1) ** 2 + k**2)
    np.testing.assert_allclose(conductor_rgb(metal), expected, rtol=1e-5)


def test_every_render_setting_is_set_and_recorded(cycles_scene):
    settings = RenderSettings(max_depth=6, renderer_options={"light_tree": True})
    _, attrs = cycles_scene.render_with_attrs("left", spp=2, seed=2**32 - 5, settings=settings)
    c = bpy.context.scene.cycles
    assert (c.device, c.use_denoising, c.use_adaptive_sampling) == ("CPU", False, False)
    assert c.use_light_tree and attrs["cycles_light_tree"]  # turned on, and recorded
    assert (c.sample_clamp_direct, c.sample_clamp_indirect) == (0.0, 0.0)
    assert c.max_bounces == attrs["cycles_max_bounces"] == bounces(6) == 4
    assert (c.pixel_filter_type, c.filter_width) == ("BOX", 1.0)
    assert bpy.context.scene.view_settings.view_transform == "Standard"
    assert attrs["cycles_seed"] == c.seed == (2**32 - 5) % 2**31
    assert bpy.context.scene.render.threads == 2


def test_seeds_reproduce_and_differ_and_the_views_get_their_own(cycles_scene):
    a = cycles_scene.render("left", spp=4, seed=11, settings=SETTINGS)
    b = cycles_scene.render("left", spp=4, seed=11, settings=SETTINGS)
    c = cycles_scene.render("left", spp=4, seed=12, settings=SETTINGS)
    np.testing.assert_array_equal(a, b)
    assert np.mean(a != c) > 0.5
    seeds = {view: cycles_seed(render_seed("lambertian", view, 4, 0)) for view in ("left", "right")}
    assert seeds["left"] != seeds["right"]


def test_geometry_is_the_ground_truths(cycles_scene):
    """Cycles' own first hits match the ground truth traced on the Mitsuba geometry: planar
    depth to 1e-3 relative on valid pixels, and the object index to the shape index."""
    gt = compute_ground_truth(cycles_scene)
    for view in ("left", "right"):
        own = cycles_scene.geometry(view)
        truth = gt.sel(view=view)
        valid = truth.valid.values
        rel = np.abs(own["depth"] - truth.depth.values)[valid] / truth.depth.values[valid]
        print(f"{view}: depth largest relative difference {rel.max():.2e}")
        assert valid.mean() > 0.8 and rel.max() < 1e-3
        hits = cycles_scene.trace(view)
        np.testing.assert_array_equal(own["object_index"] - 1, hits.shape_index)


@pytest.mark.parametrize("convention", ["paper", "conventional"])
def test_clean_right_view_warps_onto_left(convention):
    """The photometric test of tests/test_photometric.py on Cycles renders."""
    scene = prepare("cycles", convention, width=96, height=54)
    gt = compute_ground_truth(scene).sel(view="left")
    images = {
        view: scene.render(
            view, spp=512, seed=render_seed("photo", view, 512, convention), settings=SETTINGS
        )
        for view in ("left", "right")
    }
    mask = gt.valid.values & ~gt.glass.values & ~gt.occluded.values
    sign = int(gt.attrs["disparity_sign"])
    warped, omega = warp_right_to_left(images["right"], gt.disparity.values, sign=sign, valid=mask)
    error = median_relative_error(images["left"], warped, omega)
    wrong, omega_wrong = warp_right_to_left(
        images["right"], gt.disparity.values, sign=-sign, valid=mask
    )
    error_wrong = median_relative_error(images["left"], wrong, omega_wrong)
    print(f"{convention}: {100 * error:.2f}% recorded sign, {100 * error_wrong:.2f}% opposite")
    assert omega.mean() > 0.8
    assert error < 0.03
    assert error_wrong > 2 * error


def test_clean_image_matches_mitsuba_after_the_unit_conversion(cycles_scene):
    """Camera, geometry, textures and light units: the diffuse-only scene's clean left image
    in Cycles (emission strength 1 per unit radiance) against Mitsuba's."""
    spp = 1024
    cyc = cycles_scene.render("left", spp=spp, seed=5, settings=SETTINGS).astype(np.float64)
    mit = prepare("mitsuba").render("left", spp=spp, seed=5, settings=SETTINGS)
    mit = mit.astype(np.float64)
    ratio = cyc.mean(axis=(0, 1)) / mit.mean(axis=(0, 1))
    rel = np.abs(cyc - mit).mean(-1) / np.maximum(mit.mean(-1), 1e-3)
    print(
        f"mean ratio Cycles / Mitsuba per channel {np.round(ratio, 4)}, "
        f"median per-pixel relative difference {np.median(rel):.3f}"
    )
    np.testing.assert_allclose(ratio, 1.0, atol=0.02)
    assert np.median(rel) < 0.05


@pytest.mark.parametrize("pattern", ["TABULATED_SOBOL", "BLUE_NOISE"])
def test_variance_falls_with_spp_at_least_as_fast_as_one_over_spp(cycles_scene, pattern):
    """Seed-to-seed variance of the pixels of a diffuse scene against SPP.

    Cycles has no independent sampler: its sample patterns are scrambled quasi-Monte Carlo
    sequences, so the variance falls faster than 1/SPP (measured log-log slopes about
    -1.2), never slower. The slope is checked to lie in [-1.5, -0.95]: slower would mean
    correlated seeds or a sample count not honoured.
    """
    spps, n = (4, 16, 64), 8
    settings = RenderSettings(max_depth=4, renderer_options={"sampling_pattern": pattern})
    means = []
    for spp in spps:
        stack = np.stack(
            [
                cycles_scene.render("left", spp=spp, seed=1000 * spp + k, settings=settings)
                for k in range(n)
            ]
        ).astype(np.float64)
        means.append(stack.var(axis=0, ddof=1).mean())
    slope = np.polyfit(np.log(spps), np.log(means), 1)[0]
    print(f"{pattern}: variance {np.round(means, 6)} at SPP {spps}: slope {slope:.3f}")
    assert -1.5 <= slope <= -0.95


@pytest.mark.workflow
def test_two_renderers_run_end_to_end_and_are_compared(tmp_path):
    """`renderers: [mitsuba, cycles]` on the tiny config: each renderer's whole experiment,
    one shared ground truth, the cross-renderer table (whose rows are the renderers' own
    correlation rows) and figure; a rerun does nothing."""
    from stereovar.io.tables import read_rows

    from .test_workflow import TINY, copy_workflow, planned_jobs, snakemake

    root = copy_workflow(tmp_path / "wf", {**TINY, "renderers": ["mitsuba", "cycles"]})
    snakemake(root, "-j2", "all")
    table = read_rows(root / "results/tables/cross_renderer.csv")
    assert (root / "results/figures/cross_renderer.png").stat().st_size > 0
    spp = TINY["render"]["spp"]
    for renderer in ("mitsuba", "cycles"):
        stores = list((root / f"results/{renderer}/renders").rglob("seeds*.zarr"))
        assert stores
        for scene in TINY["scenes"]:
            own = {
                (r["region"], r["method"]): r
                for r in read_rows(
                    root / f"results/{renderer}/seeds/correlation/{scene}/spp{spp}.csv"
                )
            }
            for row in (t for t in table if t["scene"] == scene):
                expected = own[(row["region"], row["method"])]["rho"]
                assert row[f"rho_{renderer}"] == pytest.approx(expected, nan_ok=True)
    from stereovar.io.store import open_dataset

    attrs = open_dataset(next((root / "results/cycles/renders").rglob("seeds*.zarr"))).attrs
    assert attrs["renderer"] == "cycles" and '"denoise": false' in attrs["renderer_options"]
    assert attrs["cycles_pixel_filter"] == "BOX 1 px" and attrs["cycles_device"] == "CPU"
    assert planned_jobs(root, "all") == {}
