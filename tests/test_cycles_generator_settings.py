"""Cycles' render-time settings that data generators ship with (``render.cycles``): adaptive
sampling, Cycles' OIDN denoiser (render settings or compositor), multiview stereo and the seed
rules. Each is checked through ``bpy``'s own settings after set-up, and by what it does to
the renders: the residual correlation of the two views that each seed rule implies, and the
variance a denoiser removes.

One scene at 32x24 px and a 1e-6 m baseline serves the module: the two views then see the
same pixels (zero disparity), so their residuals correlate at about 1 when they share a seed
and about 0 when they do not. bpy wheels exist for CPython 3.11 only.
"""

import sys

import numpy as np
import pytest

if sys.version_info[:2] != (3, 11):
    pytest.skip("bpy wheels exist for CPython 3.11 only", allow_module_level=True)

import bpy  # noqa: E402

from stereovar.config import validate_config  # noqa: E402
from stereovar.errors import ConfigError  # noqa: E402
from stereovar.renderers import get_renderer  # noqa: E402
from stereovar.renderers.base import RenderSettings  # noqa: E402
from stereovar.renderers.cycles.render import multiview_rig, set_stereo_camera  # noqa: E402
from stereovar.renderers.cycles.scene import camera_matrix  # noqa: E402
from stereovar.renderers.cycles.settings import (  # noqa: E402
    adaptive_first_stop,
    apply_settings,
    integrator_seed,
    sampler_seed,
)
from stereovar.rig import VIEWS, make_rig  # noqa: E402

from .test_photometric import lambertian_spec  # noqa: E402

SCHEMA = "workflow/schemas/config.schema.yaml"
WIDTH, HEIGHT, TINY_BASELINE = 32, 24, 1e-6
MAX_DEPTH = 4


@pytest.fixture(scope="module")
def scene():
    """The diffuse test room at a 1e-6 m baseline, paper convention (whose multiview eyes
    are Blender's swapped)."""
    rig = {"width": WIDTH, "height": HEIGHT, "baseline_m": TINY_BASELINE, "convention": "paper"}
    return get_renderer("cycles").prepare(lambertian_spec(), rig=rig, threads=2)


def settings(**options):
    return RenderSettings(max_depth=MAX_DEPTH, renderer_options=options)


def apply(**options):
    """Set the Cycles settings of one render on Blender's scene; their attrs."""
    return apply_settings(
        bpy.context.scene, spp=16, seed=7, max_depth=MAX_DEPTH, threads=2, options=options
    )


def residual_correlation(left, right) -> tuple[float, float]:
    r"""Pearson correlation of the two views' residuals (render minus the mean of the
    replicates), on the luminance of every pixel of every replicate, and its standard error
    were the residuals independent:

    .. math:: \mathrm{se} = \sqrt{\textstyle\sum_i a_i^2 b_i^2} \Big/
        \sqrt{\textstyle\sum_i a_i^2 \sum_i b_i^2}

    (the spread of :math:`\sum_i a_i b_i` given the residuals' sizes;
    :math:`1/\sqrt{n}` for :math:`n` Gaussian residuals, larger for the heavy-tailed
    residuals of a path tracer).
    """
    a = left.mean(-1) - left.mean(-1).mean(0)
    b = right.mean(-1) - right.mean(-1).mean(0)
    norm = np.sqrt((a * a).sum() * (b * b).sum())
    return float((a * b).sum() / norm), float(np.sqrt((a * a * b * b).sum()) / norm)


# --------------------------------------------------------------------------------------------
# the config keys
# --------------------------------------------------------------------------------------------


def test_generator_settings_validate_and_contradictions_are_one_line():
    for cycles in (
        {"denoise": True, "denoiser": "compositor", "denoising_input_passes": "RGB_ALBEDO"},
        {"adaptive_sampling": True, "adaptive_threshold": 0.005, "adaptive_min_samples": 0},
        {"multiview": True, "seed": "unset"},
        {"seed": "animated"},
    ):
        validate_config({"render": {"renderer": "cycles", "cycles": cycles}}, SCHEMA)
    for cycles, key in (
        ({"multiview": True}, "render.cycles.multiview"),  # per_view: a seed per view
        ({"seed": "random"}, "render.cycles.seed"),
        ({"denoiser": "optix"}, "render.cycles.denoiser"),
        ({"adaptive_min_samples": -1}, "render.cycles.adaptive_min_samples"),
        ({"view_transform": "AgX"}, "render.cycles.view_transform"),
    ):
        with pytest.raises(ConfigError) as err:
            validate_config({"render": {"renderer": "cycles", "cycles": cycles}}, SCHEMA)
        message = str(err.value)
        assert "\n" not in message and key in message, message


# --------------------------------------------------------------------------------------------
# each setting, through bpy's own settings
# --------------------------------------------------------------------------------------------


def test_adaptive_settings_reach_blender(scene):
    c = bpy.context.scene.cycles
    attrs = apply()
    assert not c.use_adaptive_sampling and not attrs["cycles_adaptive_sampling"]
    attrs = apply(adaptive_sampling=True, adaptive_threshold=0.005, adaptive_min_samples=12)
    assert c.use_adaptive_sampling and attrs["cycles_adaptive_sampling"]
    assert c.adaptive_threshold == pytest.approx(0.005) == attrs["cycles_adaptive_threshold"]
    assert c.adaptive_min_samples == 12 == attrs["cycles_adaptive_min_samples"]


@pytest.mark.parametrize(
    "threshold, min_samples",
    [(0.01, 0), (0.1, 20)],  # Cycles' automatic minimum (64, first stop 80); a set one (32)
)
def test_no_pixel_stops_before_cycles_first_adaptive_stop(scene, threshold, min_samples):
    """Adaptive sampling leaves a render of up to :func:`adaptive_first_stop` samples bit for
    bit the render without it, and changes it 16 samples later: Cycles' minimum (automatic:
    ``max(4, ceil(16 / threshold^0.3))``) and its 16-sample filter step, measured."""
    adaptive = {
        "adaptive_sampling": True,
        "adaptive_threshold": threshold,
        "adaptive_min_samples": min_samples,
    }
    first = adaptive_first_stop(threshold, min_samples, 1024)
    assert first == (80 if min_samples == 0 else 32)
    for spp, same in ((first, True), (first + 16, False)):
        plain = scene.render("left", spp=spp, seed=5, settings=settings())
        on, attrs = scene.render_with_attrs("left", spp=spp, seed=5, settings=settings(**adaptive))
        assert attrs["cycles_adaptive_first_stop"] == first
        assert np.array_equal(plain, on) is same, (spp, np.abs(plain - on).max())


@pytest.mark.parametrize("passes", ["RGB", "RGB_ALBEDO", "RGB_ALBEDO_NORMAL"])
def test_denoisers_reach_blender(scene, passes):
    s = bpy.context.scene
    c, layer = s.cycles, s.view_layers[0]
    attrs = apply(denoise=True, denoiser="render", denoising_input_passes=passes)
    assert (c.use_denoising, c.denoiser, c.denoising_input_passes) == (
        True,
        "OPENIMAGEDENOISE",
        passes,
    )
    assert s.compositing_node_group is None
    assert (attrs["cycles_denoiser"], attrs["cycles_denoising_input_passes"]) == ("render", passes)

    attrs = apply(denoise=True, denoiser="compositor", denoising_input_passes=passes)
    assert not c.use_denoising and s.render.use_compositing
    group = s.compositing_node_group
    denoise = next(n for n in group.nodes if n.bl_idname == "CompositorNodeDenoise")
    source = {
        socket: denoise.inputs[socket].links[0].from_socket.name
        for socket in ("Image", "Albedo", "Normal")
        if denoise.inputs[socket].is_linked
    }
    expected = {"Image": "Image"}
    if passes != "RGB":
        expected["Albedo"] = "Diffuse Color"
    if passes == "RGB_ALBEDO_NORMAL":
        expected["Normal"] = "Normal"
    assert source == expected
    assert layer.use_pass_diffuse_color == ("Albedo" in expected)
    assert layer.use_pass_normal == ("Normal" in expected)
    (output,) = [n for n in group.nodes if n.bl_idname == "NodeGroupOutput"]
    assert output.inputs[0].links[0].from_node == denoise
    assert attrs["cycles_denoiser"] == "compositor"

    attrs = apply(denoiser="compositor")  # denoise off: nothing of it is left on
    assert not c.use_denoising and s.compositing_node_group is None
    assert not (layer.use_pass_diffuse_color or layer.use_pass_normal)
    assert (attrs["cycles_denoise"], attrs["cycles_denoiser"]) == (False, "none")


def test_seed_rules_reach_blender(scene):
    s = bpy.context.scene
    c = s.cycles
    attrs = apply_settings(
        s, spp=4, seed=2**32 - 5, max_depth=MAX_DEPTH, threads=2, options={"seed": "per_view"}
    )
    assert (c.seed, c.use_animated_seed, s.frame_current) == ((2**32 - 5) % 2**31, False, 1)
    assert attrs["cycles_seed_rule"] == "per_view"
    options = {"seed": "animated"}
    frame = sampler_seed("lambertian", "right", 4, 6, policy="independent", options=options)
    attrs = apply_settings(s, spp=4, seed=frame, max_depth=MAX_DEPTH, threads=2, options=options)
    assert (c.seed, c.use_animated_seed, s.frame_current) == (0, True, 7)
    assert (attrs["cycles_frame"], attrs["cycles_seed_rule"]) == (7, "animated")


def test_animated_seed_is_blenders_hash_of_frame_and_seed(scene):
    """An animated-seed render at frame f is, bit for bit, the render whose ``cycles.seed``
    is Cycles' ``hash_uint2(f, 0)`` (:func:`integrator_seed`)."""
    frame = next(f for f in range(1, 64) if integrator_seed(0, animated=True, frame=f) < 2**31)
    animated, attrs = scene.render_with_attrs(
        "left", spp=4, seed=frame, settings=settings(seed="animated")
    )
    hashed = integrator_seed(0, animated=True, frame=frame)
    assert attrs["cycles_integrator_seed"] == hashed
    np.testing.assert_array_equal(
        animated, scene.render("left", spp=4, seed=hashed, settings=settings())
    )
    other = scene.render("left", spp=4, seed=frame + 1, settings=settings(seed="animated"))
    assert np.mean(animated != other) > 0.5


@pytest.mark.parametrize("convention", ["paper", "conventional"])
def test_multiview_eyes_are_the_rig_views(scene, convention):
    """Blender's own eye matrices (``RenderEngine.camera_model_matrix`` of each active view,
    read by a probe engine) after the multiview set-up equal the rig's poses of the views
    they stand for."""
    left = scene.rig.to_world["left"]
    rig = make_rig(
        left,
        scene.rig.fov_deg,
        width=WIDTH,
        height=HEIGHT,
        baseline_m=0.08,
        convention=convention,
    )
    s = bpy.context.scene
    apply(multiview=True, seed="unset")
    stereo, attrs = set_stereo_camera(s, scene.camera, rig)
    assert s.render.use_multiview and s.render.views_format == "STEREO_3D"
    cam = scene.camera.data.stereo
    assert (cam.convergence_mode, cam.pivot) == ("PARALLEL", stereo.pivot)
    assert cam.interocular_distance == pytest.approx(0.08, rel=1e-6)
    assert stereo.pivot == ("RIGHT" if convention == "paper" else "LEFT")

    seen = {}

    class Probe(bpy.types.RenderEngine):
        bl_idname = "STEREOVAR_EYE_PROBE"
        bl_label = "eye probe"

        def render(self, depsgraph):
            for eye in VIEWS:
                self.active_view_set(eye)
                matrix = self.camera_model_matrix(
                    depsgraph.scene.camera, use_spherical_stereo=False
                )
                seen[eye] = np.array(matrix, dtype=np.float64)
            result = self.begin_result(0, 0, WIDTH, HEIGHT)
            self.end_result(result)

    bpy.utils.register_class(Probe)
    try:
        s.render.engine = Probe.bl_idname
        bpy.ops.render.render()
    finally:
        bpy.utils.unregister_class(Probe)
        s.render.engine = "CYCLES"
    for view in VIEWS:
        expected = camera_matrix(rig.to_world[view])
        np.testing.assert_allclose(seen[stereo.eyes[view]], expected, atol=1e-6)
    # the other view is really 8 cm away: the check can tell the eyes apart
    assert np.abs(seen["left"][:3, 3] - seen["right"][:3, 3]).max() > 0.05


def test_multiview_refuses_a_rig_a_stereo_camera_cannot_express(scene):
    rig = scene.rig
    tilted = dict(rig.to_world)
    tilted["right"] = tilted["right"].copy()
    tilted["right"][:3, 3] += tilted["left"][:3, 1] * 0.01  # moved along the image y axis
    with pytest.raises(ConfigError, match="render.cycles.multiview.*set render.cycles.multiview"):
        multiview_rig(type(rig)(**{**rig.__dict__, "to_world": tilted}))


def test_multiview_renders_each_seed_once_and_seeds_the_second_eye_as_cycles_does(
    scene, monkeypatch
):
    """The render job's order (views outer, seeds inner) renders each seed once; Blender's
    first eye (the rig's right view here, paper convention) is the single render with that
    seed, the other the single render with Cycles' re-seeded ``seed + h(seed, h(0xdeadbeef,
    0))``, bit for bit."""
    from stereovar.renderers.cycles import render as cycles_render

    calls = []
    real = cycles_render.render_pair

    def counted(*args, **kwargs):
        calls.append(kwargs["seed"])
        return real(*args, **kwargs)

    monkeypatch.setattr(cycles_render, "render_pair", counted)
    seeds = [s for s in range(40) if integrator_seed(s, view_index=1) < 2**31][:3]
    mv = settings(multiview=True, seed="unset")
    images = {
        view: [scene.render(view, spp=4, seed=s, settings=mv) for s in seeds] for view in VIEWS
    }
    assert calls == seeds and not scene._other_eyes
    stereo = multiview_rig(scene.rig)
    first = next(view for view in VIEWS if stereo.eyes[view] == "left")
    second = next(view for view in VIEWS if view != first)
    for k, seed in enumerate(seeds):
        same = scene.render(first, spp=4, seed=seed, settings=settings())
        np.testing.assert_array_equal(images[first][k], same)
        reseeded = integrator_seed(seed, view_index=1)
        other = scene.render(second, spp=4, seed=reseeded, settings=settings())
        np.testing.assert_array_equal(images[second][k], other)


# --------------------------------------------------------------------------------------------
# what the settings do to the renders
# --------------------------------------------------------------------------------------------

N_REPLICATES, N_DENOISED, SPP = 8, 4, 4


@pytest.mark.parametrize(
    "options, shared",
    [
        ({"seed": "per_view"}, False),
        ({"seed": "unset"}, True),
        ({"seed": "animated"}, True),
        # one cycles.seed, but Cycles re-seeds the second eye: independent noise
        ({"seed": "unset", "multiview": True}, False),
    ],
    ids=["per_view", "unset", "animated", "multiview"],
)
def test_seed_rules_give_the_residual_correlation_they_imply(scene, options, shared):
    """At zero disparity (1e-6 m baseline) the views' residuals correlate at about 1 (above
    0.95) when both views sample with one seed, and not at all otherwise: |r| below 4
    standard errors of the correlation of independent residuals (:func:`residual_correlation`; about
    1/sqrt(pixels x (replicates - 1)) were they Gaussian)."""
    stacks = {
        view: np.stack(
            [
                scene.render(
                    view,
                    spp=SPP,
                    seed=sampler_seed(
                        "lambertian", view, SPP, index, policy="independent", options=options
                    ),
                    settings=settings(**options),
                )
                for index in range(N_REPLICATES)
            ]
        ).astype(np.float64)
        for view in VIEWS
    }
    r, se = residual_correlation(stacks["left"], stacks["right"])
    gaussian = 1.0 / np.sqrt(WIDTH * HEIGHT * (N_REPLICATES - 1))
    print(f"{options}: residual correlation of the views {r:.4f} (se {se:.4f}, {gaussian:.4f})")
    if shared:  # the views differ only where a 1e-6 m shift moves a path
        assert r > 0.95
    else:
        assert 4 * se < 0.1  # enough residuals to tell no correlation from some
        assert abs(r) < 4 * se


@pytest.mark.parametrize("denoiser", ["render", "compositor"])
def test_a_denoised_render_varies_less_across_seeds(scene, denoiser):
    """OIDN removes most of the seed-to-seed variance (its output read back as the linear
    radiance it denoised: the image mean stays that of the noisy renders)."""
    on = settings(denoise=True, denoiser=denoiser)
    stacks = {
        name: np.stack(
            [scene.render("left", spp=SPP, seed=100 + k, settings=s) for k in range(N_DENOISED)]
        ).astype(np.float64)
        for name, s in (("noisy", settings()), ("denoised", on))
    }
    variance = {name: float(stack.var(axis=0, ddof=1).mean()) for name, stack in stacks.items()}
    mean = {name: float(stack.mean()) for name, stack in stacks.items()}
    print(f"{denoiser}: variance across seeds {variance}, image mean {mean}")
    assert variance["denoised"] < 0.5 * variance["noisy"]
    assert mean["denoised"] == pytest.approx(mean["noisy"], rel=0.05)


def test_every_setting_is_in_the_render_cache_key(tmp_path):
    """A render job keys each render on every ``render.cycles`` setting, and under a shared
    seed rule gives both views of a replicate one sampler seed (recorded as policy shared)."""
    import yaml

    from stereovar.io.cache import render_key
    from stereovar.jobs.render import _Job
    from stereovar.renderers.cycles.settings import CYCLES_DEFAULTS, cycles_options

    path = tmp_path / "lambertian.yaml"
    path.write_text(yaml.safe_dump(lambertian_spec()))
    rig = {"width": WIDTH, "height": HEIGHT, "baseline_m": 0.08, "convention": "paper"}

    def job(**cycles):
        return _Job(
            path,
            spp=SPP,
            renderer="cycles",
            variant="auto",
            seed_policy="independent",
            threads=2,
            cache=None,
            options={**rig, "max_depth": MAX_DEPTH, "renderer_options": cycles_options(cycles)},
        )

    def key(j, view="left", index=0):
        return render_key({**j.key_base, "view": view, "sampler_seed": j.seed(view, index)})

    base = job()
    changed = {
        "denoise": True,
        "denoiser": "compositor",
        "denoising_input_passes": "RGB",
        "adaptive_sampling": True,
        "adaptive_threshold": 0.005,
        "adaptive_min_samples": 8,
        "seed": "unset",
    }
    older = {"view_transform", "light_tree", "clamp_direct", "clamp_indirect", "sampling_pattern"}
    assert set(changed) | {"multiview"} == set(CYCLES_DEFAULTS) - older
    for name, value in changed.items():
        assert key(job(**{name: value})) != key(base), name
    assert key(job(seed="unset", multiview=True)) != key(job(seed="unset"))
    assert base.attrs["seed_policy"] == "independent"
    assert base.seed("left", 3) != base.seed("right", 3)
    unset = job(seed="unset")
    assert unset.attrs["seed_policy"] == "shared"
    assert unset.seed("left", 3) == unset.seed("right", 3) != unset.seed("left", 4)
    animated = job(seed="animated", multiview=True)
    assert animated.seed("left", 3) == animated.seed("right", 3) == 4
