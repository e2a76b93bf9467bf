"""The Cycles renderer (render.renderer: cycles) against the renderer-neutral ground truth and
against Mitsuba, at tiny sizes; and its frames as Blender itself writes them, audited against
the native measurement.

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
    assert "\n" not in message and "stereovar[cycles]" in message and "render.renderer" in message


@pytest.mark.parametrize(
    "cycles, key",
    [
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

    # one scene, the sweep at the main SPP: each renderer's experiment once, every stage kept
    scenes = TINY["scenes"][:1]
    config = {
        **TINY,
        "scenes": scenes,
        "renderers": ["mitsuba", "cycles"],
        "render": {**TINY["render"], "spp_sweep": {"scene": scenes[0], "spp": [2]}},
    }
    root = copy_workflow(tmp_path / "wf", config)
    snakemake(root, "-j2", "all")
    table = read_rows(root / "results/tables/cross_renderer.csv")
    assert (root / "results/figures/cross_renderer.png").stat().st_size > 0
    spp = TINY["render"]["spp"]
    for renderer in ("mitsuba", "cycles"):
        stores = list((root / f"results/{renderer}/renders").rglob("seeds*.zarr"))
        assert stores
        for scene in scenes:
            own = {
                (r["region"], r["method"]): r
                for r in read_rows(
                    root / f"results/{renderer}/seeds/correlation/{scene}/spp{spp}.csv"
                )
            }
            rows = [t for t in table if t["scene"] == scene]
            assert rows
            for row in rows:
                expected = own[(row["region"], row["method"])]["rho"]
                assert row[f"rho_{renderer}"] == pytest.approx(expected, nan_ok=True)
    from stereovar.io.store import open_dataset

    attrs = open_dataset(next((root / "results/cycles/renders").rglob("seeds*.zarr"))).attrs
    assert attrs["renderer"] == "cycles" and '"denoise": false' in attrs["renderer_options"]
    assert attrs["cycles_pixel_filter"] == "BOX 1 px" and attrs["cycles_device"] == "CPU"
    assert planned_jobs(root, "all") == {}


AUDIT_SPP, AUDIT_SEEDS = 16, 8
AUDITED = {
    "scenes": ["lambertian"],
    "resolution": {"width": WIDTH, "height": HEIGHT},
    # right camera to the image-right: x_R = x_L - d, the audit's default convention
    "rig": {"baseline_m": BASELINE, "convention": "conventional"},
    "render": {
        "renderer": "cycles",
        "spp": AUDIT_SPP,
        "n_seeds": AUDIT_SEEDS,
        "seeds_per_job": AUDIT_SEEDS,
        "max_depth": 4,
        "spp_sweep": {"scene": "lambertian", "spp": [AUDIT_SPP]},
    },
    "preview": {"spp": 4},
    "mitigations": {"names": []},
}
BLENDER_PARTS = {
    "ViewLayer.Combined": {"ViewLayer.Combined"},  # R, G, B, A: the bindings group them
    "ViewLayer.Depth": {"ViewLayer.Depth.Z"},
    "ViewLayer.Object Index": {"ViewLayer.Object Index.X"},
}
"""What Blender 5 writes to an OPEN_EXR_MULTILAYER file with the Combined, Depth and Object
Index passes: one part per pass, each channel named view layer, pass, channel."""


def blender_file_output(path, *, spp: int, seed: int) -> None:
    """What a data team's bpy script does once the camera is placed: set its sampler, keep
    the colour linear, turn on the Depth (Z) and Object Index passes and let Blender write
    the render as a float multilayer OpenEXR (lossless ZIP, Blender's default codec;
    ``dither_intensity`` left at Blender's default, which only touches 8-bit output)."""
    scene = bpy.context.scene
    c = scene.cycles
    c.samples, c.seed, c.use_animated_seed = spp, seed, False
    c.use_denoising = c.use_adaptive_sampling = False
    scene.view_settings.view_transform, scene.view_settings.look = "Standard", "None"
    layer = scene.view_layers["ViewLayer"]
    layer.use_pass_combined = layer.use_pass_z = layer.use_pass_object_index = True
    out = scene.render.image_settings
    out.media_type, out.file_format = "MULTI_LAYER_IMAGE", "OPEN_EXR_MULTILAYER"
    out.color_depth, out.exr_codec = "32", "ZIP"
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)


def blender_focal_px(width: int) -> float:
    """The focal length in pixels a team reads off its Blender camera (sensor width fit)."""
    camera = bpy.context.scene.camera.data
    assert camera.type == "PERSP" and camera.sensor_fit in ("AUTO", "HORIZONTAL")
    return camera.lens / camera.sensor_width * width


@pytest.mark.workflow
def test_renders_blender_wrote_audit_to_the_native_verdict(tmp_path):
    """The same frames measured natively (render.renderer: cycles through the workflow) and
    audited from the files Blender itself writes: a multilayer EXR per render (Combined,
    Depth and Object Index passes) and the Depth pass as disparity f B / z in a PFM, with
    the same scene, rig, seeds and settings.

    Float32 EXR is lossless and Blender dithers only 8-bit output, so the audit reads the
    native pixels bit for bit. Blender's Depth pass is planar depth at the first hit of the
    pixel-centre ray (the same for every seed), so f B / z is the ground-truth disparity to
    float32 rounding (1e-4 px). The audit's valid pixels are the native ones, its
    intervention rows equal, and its statistics and verdict rows differ only through that
    rounding of the warp's disparity.
    """
    import OpenEXR
    import yaml

    from stereovar import layout
    from stereovar.audit.verdict import verdict, verdict_rows
    from stereovar.io.images import read_image
    from stereovar.io.renders import LazyRenders
    from stereovar.io.store import open_dataset
    from stereovar.io.tables import read_rows
    from stereovar.io.writers import write_field
    from stereovar.jobs.common import prepare_scene
    from stereovar.renderers.cycles.settings import cycles_seed
    from stereovar.renderers.quiet import silenced

    from .test_audit_workflow import NUMBERS
    from .test_workflow import copy_workflow, snakemake

    scene_name, spp = "lambertian", AUDIT_SPP
    root = copy_workflow(tmp_path / "wf", AUDITED)
    spec = {**lambertian_spec(), "name": scene_name}
    (root / f"scenes/{scene_name}.yaml").write_text(yaml.safe_dump(spec))
    native_rows = layout.correlation_rows("cycles", "seeds", scene_name, spp)
    native_intervention = layout.intervention_metrics("cycles", "seeds", scene_name)
    snakemake(root, "-j2", native_rows, native_intervention)
    gt = open_dataset(root / layout.ground_truth_store("cycles", scene_name))
    native = {
        view: sorted((root / f"results/cycles/renders/{scene_name}/{view}").rglob("seeds*.zarr"))
        for view in ("left", "right")
    }

    # the team's frames: the same scene, rig, seeds and settings, saved by Blender
    prepared = prepare_scene(
        root / f"scenes/{scene_name}.yaml",
        renderer="cycles",
        threads=2,
        width=WIDTH,
        height=HEIGHT,
        baseline_m=BASELINE,
        convention="conventional",
    )
    settings = RenderSettings(max_depth=4)
    team = root / "team"
    layer = bpy.context.scene.view_layers["ViewLayer"]
    depth = {}
    try:
        for view, letter in (("left", "L"), ("right", "R")):
            (stored,) = native[view]
            sampler_seeds = open_dataset(stored)["sampler_seed"].values
            assert len(sampler_seeds) == AUDIT_SEEDS
            images = LazyRenders([stored])
            for k, (seed, image) in enumerate(zip(sampler_seeds, images, strict=True)):
                # places the camera and sets every setting, as the workflow's render job did
                again = prepared.render(view, spp=spp, seed=int(seed), settings=settings)
                np.testing.assert_array_equal(again, image)
                path = team / letter / f"seed_{k}.exr"
                with silenced(1):  # Blender's per-render lines
                    blender_file_output(path, spp=spp, seed=cycles_seed(seed))
                exr = OpenEXR.File(str(path))
                parts = {p.name(): set(p.channels) for p in exr.parts}
                assert parts == BLENDER_PARTS, parts
                header = exr.parts[0].header
                assert str(header["compression"]).endswith("ZIP_COMPRESSION")
                combined = exr.parts[0].channels["ViewLayer.Combined"].pixels
                assert combined.dtype == np.float32 and combined.shape == (HEIGHT, WIDTH, 4)
                z = exr.parts[1].channels["ViewLayer.Depth.Z"].pixels
                index = exr.parts[2].channels["ViewLayer.Object Index.X"].pixels
                if view in depth:  # the pixel-centre first hit, whatever the seed
                    np.testing.assert_array_equal(z, depth[view][0])
                depth[view] = (z, index)
                # float32 multilayer EXR is lossless: the native pixels, bit for bit
                np.testing.assert_array_equal(read_image(path), image)
    finally:
        layer.use_pass_z = layer.use_pass_object_index = False

    focal = blender_focal_px(WIDTH)
    assert focal == pytest.approx(gt.attrs["focal_px"], rel=1e-6)
    u = (np.arange(WIDTH) + 0.5 - WIDTH / 2) / focal
    v = (np.arange(HEIGHT) + 0.5 - HEIGHT / 2) / focal
    ray_length = np.sqrt(1 + u[None, :] ** 2 + v[:, None] ** 2)  # per unit planar depth
    for view, letter in (("left", "L"), ("right", "R")):
        z, index = (a.astype(np.float64) for a in depth[view])
        truth = gt.sel(view=view)
        # the first hit of the pixel-centre ray: Cycles' own geometry render, exactly
        np.testing.assert_array_equal(z, prepared.geometry(view)["depth"])
        # the same object as the ground truth's trace (Mitsuba's geometry) but where a
        # centre ray grazes an edge and the two ray tracers part (1 right pixel here)
        same = truth.valid.values & (np.rint(index) - 1 == truth.shape_index.values)
        assert (truth.valid.values & ~same).sum() <= 2
        planar = truth.depth.values
        rel = np.abs(z - planar)[same] / planar[same]
        as_distance = np.abs(z * ray_length - planar)[same] / planar[same]
        # planar depth (z along the camera axis), not the distance along the ray
        assert rel.max() < 1e-3 and as_distance.max() > 0.2, (rel.max(), as_distance.max())
        disparity = focal * BASELINE / z  # d = f B / z
        here = same & ~truth.occluded.values
        error = np.abs(disparity - truth.disparity.values)[here]
        print(
            f"{view}: Depth.Z vs planar depth largest relative difference {rel.max():.1e} "
            f"(as ray distance {as_distance.max():.2f}); f B / z vs ground-truth disparity "
            f"largest {error.max():.1e} px on {here.sum()} non-occluded pixels; "
            f"{(truth.valid.values & ~same).sum()} pixels hit another object"
        )
        assert error.max() < 1e-3
        (team / "disparity").mkdir(exist_ok=True)
        write_field(team / "disparity" / f"{letter}.pfm", disparity.astype(np.float32))

    audit = {
        "name": "blender",
        "renders": "team/{view}/seed_{seed}.exr",
        "frame": scene_name,
        "views": {"left": "L", "right": "R"},
        "disparity": "team/disparity/{view}.pfm",
        "convention": "conventional",  # the photometric sign check runs (sign_check: stop)
        "spp": spp,
    }
    snakemake(root, "-j2", "all", config={**AUDITED, "audit": audit})
    base = root / "results/audit/blender"
    imported = open_dataset(base / f"ground_truth/{scene_name}.zarr")
    # the photometric sign check ran (sign_check: stop) and settled the declared convention
    check = {k: imported.attrs[f"sign_check_{k}"] for k in ("error", "opposite_error")}
    assert imported.attrs["convention"] == "conventional" and imported.attrs["disparity_sign"] == -1
    assert check["opposite_error"] > 2 * check["error"], check
    left = imported.sel(view="left")
    assert (left.valid.values == gt.valid.sel(view="left").values).all()
    # how far the audit's warp disparity is from the native one: the tolerance below
    eps = float(
        np.abs(left.disparity.values - gt.disparity.sel(view="left").values)[
            left.valid.values
        ].max()
    )
    assert eps < 5e-4
    for view in ("left", "right"):  # the imported stores hold the native pixels
        (store,) = sorted((base / f"renders/{scene_name}/{view}").rglob("seeds*.zarr"))
        np.testing.assert_array_equal(
            np.stack(list(LazyRenders([store]))), np.stack(list(LazyRenders(native[view])))
        )

    # Eq. 3 and the verdict, native against audited. The variance fields are the same bits;
    # only the warp's disparity differs, by at most eps px. Bilinear warping moves each
    # warped value by at most eps times the difference of two neighbouring pixels, so the
    # statistics and their interval bounds move by a few eps at most: 2 eps is allowed, 4 eps
    # for the attenuation-corrected rho (divided by sqrt(reliabilities), about 0.6 here).
    # The intervention searches whole-pixel disparities: its rows are equal.
    run = f"{base.relative_to(root)}/seeds"
    audited = {
        "correlation": read_rows(root / f"{run}/correlation/{scene_name}/spp{spp}.csv"),
        "intervention": read_rows(root / f"{run}/intervention/{scene_name}.csv"),
    }
    natively = {
        "correlation": read_rows(root / native_rows),
        "intervention": read_rows(root / native_intervention),
    }
    ours = {(r["method"]): r for r in natively["correlation"] if r["region"] == "all"}
    theirs = {(r["method"]): r for r in audited["correlation"] if r["region"] == "all"}
    assert ours.keys() == theirs.keys()
    worst = 0.0
    for method, n in ours.items():
        a = theirs[method]
        assert (a["n_pixels"], a["mean_a"]) == (n["n_pixels"], n["mean_a"]), method
        for col in NUMBERS:
            if col == "mean_a" or np.isnan(float(n[col])):
                assert np.isnan(float(a[col])) == np.isnan(float(n[col])), (method, col)
                continue
            tol = (4 if col == "rho_corrected" else 2) * eps
            diff = abs(float(a[col]) - float(n[col]))
            assert diff <= tol, (method, col, n[col], a[col])
            worst = max(worst, diff)

    def lifts(rows):
        return {
            (r["source"], r["cost"], r["metric"], r["condition"]): (r["value"], r["n_pixels"])
            for r in rows
            if r["region"] == "all"
        }

    assert lifts(audited["intervention"]) == lifts(natively["intervention"])
    native_verdict = verdict_rows(natively["correlation"], natively["intervention"])
    audit_verdict = verdict_rows(audited["correlation"], audited["intervention"])
    summary = yaml.safe_load((base / "summary.json").read_text())
    page = {r["quantity"]: r for r in summary["rows"] if r["region"] == "all"}
    # region all: the audit has no material mask, so no glass or non_glass rows
    native_all, audit_all = (
        [r for r in rows if r["region"] == "all"] for rows in (native_verdict, audit_verdict)
    )
    for n, a in zip(native_all, audit_all, strict=True):
        assert n["quantity"] == a["quantity"]
        tol = (4 if n["quantity"].startswith("attenuation") else 2) * eps
        for col in ("value", "low", "high"):
            assert a[col] == pytest.approx(n[col], abs=tol), (n["quantity"], col)
            assert page[n["quantity"]][col] == pytest.approx(n[col], abs=5e-5 + tol)
    # the same verdict as the native rows give, whichever it is on these tiny frames: read
    # without a null on both sides, and the page's own against the audit's matched null
    expected = verdict(native_verdict)
    assert expected["mc_specific"] is not None
    assert verdict(audit_verdict)["mc_specific"] is expected["mc_specific"]
    own = verdict(summary["rows"])
    assert own["matched_null"] is summary["matched_null"] is True
    assert summary["mc_specific"] is own["mc_specific"]
    assert summary["strength"] == own["strength"]
    assert summary["matching_cue"] == own["matching_cue"]

    def row(rows, quantity):
        r = next(r for r in rows if r["quantity"].startswith(quantity) and r["region"] == "all")
        return f"{r['value']:.6f} [{r['low']:.6f}, {r['high']:.6f}]"

    for quantity in ("Pearson", "intensity-controlled", "C_sigma WTA accuracy minus chance, r"):
        print(
            f"{quantity}: native {row(native_verdict, quantity)}, "
            f"audit {row(audit_verdict, quantity)}"
        )
    print(
        f"verdict: {expected['strength']} Monte Carlo-specific cue "
        f"(mc_specific {summary['mc_specific']}, matching cue {summary['matching_cue']}, "
        f"light {summary['light']}); sign check: median error {check['error']:.3f} declared, "
        f"{check['opposite_error']:.3f} opposite; warp disparity within {eps:.1e} px; largest "
        f"row difference {worst:.1e} (tolerance {2 * eps:.1e})"
    )
