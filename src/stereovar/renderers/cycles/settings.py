"""Cycles render settings, each set explicitly and recorded with every render.

Every render sets, and records in its store's provenance: path tracing on the CPU device;
the sampler seed by the seed rule (:data:`SEED_RULES`); the bounce limits from
``render.max_depth``; a box pixel filter one pixel wide; the Standard view transform with
linear float output; the job's thread count. ``render.cycles`` (:data:`CYCLES_DEFAULTS`)
turns on, and records, what data generators ship with: adaptive sampling, Cycles' OIDN
denoiser (in the render settings or as a compositor node), multiview stereo (both eyes in
one render) and Blender's seed handling; the light tree and clamping. All are off by default,
which is the paper's experiment: each changes the per-pixel variance it measures (adaptive
sampling stops pixels at different sample counts, a denoiser makes the residual follow the
image, one seed for both views couples their noise), and measuring that change is what the
generator profiles are for.

A tone curve (any view transform but Standard) is not linear radiance and is refused by
:func:`cycles_options_error`, as are a pixel filter other than the box and a setting Cycles
does not have.
"""

from __future__ import annotations

import math

CYCLES_DEFAULTS = {
    "denoise": False,
    "denoiser": "render",
    "denoising_input_passes": "RGB_ALBEDO_NORMAL",
    "adaptive_sampling": False,
    "adaptive_threshold": 0.01,
    "adaptive_min_samples": 0,
    "multiview": False,
    "seed": "per_view",
    "view_transform": "Standard",
    "light_tree": False,
    "clamp_direct": 0.0,
    "clamp_indirect": 0.0,
    "sampling_pattern": "TABULATED_SOBOL",
}
"""``render.cycles`` options and their defaults (``adaptive_threshold`` and
``adaptive_min_samples`` are Cycles' own defaults)."""

SAMPLING_PATTERNS = ("TABULATED_SOBOL", "BLUE_NOISE")
"""Cycles' sample patterns (it has no independent sampler; the seed scrambles the pattern)."""

DENOISERS = ("render", "compositor")
"""Where Cycles' OpenImageDenoise runs when ``denoise`` is on.

``render``
    The render settings (``cycles.use_denoising``, denoiser ``OPENIMAGEDENOISE``, Cycles'
    own albedo and normal guides as ``denoising_input_passes`` selects): the Combined pass is
    the denoised image. Kubric's default.
``compositor``
    A compositor Denoise node (Blender's defaults: HDR, prefilter Accurate) on the render
    layer's Image, guided by the Diffuse Color pass as albedo and the Normal pass, as
    BlenderProc's ``set_denoiser("INTEL")`` wires it
    (``blenderproc/python/renderer/RendererUtility.py``, ``DiffCol`` and ``Normal``); the
    composite result is the image.
"""

DENOISING_INPUT_PASSES = ("RGB", "RGB_ALBEDO", "RGB_ALBEDO_NORMAL")
"""The guides the denoiser reads besides the noisy image (Cycles' ``denoising_input_passes``;
for the compositor, which of the Albedo and Normal inputs are linked)."""

SEED_RULES = ("per_view", "unset", "animated")
"""How a render's sampler seed reaches Cycles (``render.cycles.seed``; :func:`sampler_seed`).

``per_view``
    Every render gets its own seed from :func:`stereovar.seeding.render_seed` under the
    job's seed policy; ``cycles.seed`` is that seed mod :data:`SEED_MODULUS`.
``unset``
    What a generator that never sets ``cycles.seed`` gets (Kubric, Infinigen, BlenderProc):
    Blender's seed, the same for both views of a frame rendered as two renders. Blender's
    seed is one constant (0), so N replicates of one frame rendered that way would be N
    identical images, no variance at all. The replicates therefore keep distinct seeds while
    both views of a replicate share one: the ``shared`` seed policy's labels
    (:func:`stereovar.seeding.shared_labels`), given to ``cycles.seed`` mod
    :data:`SEED_MODULUS`.
``animated``
    ``use_animated_seed`` with ``cycles.seed`` 0 and the frame number replicate index + 1:
    Cycles then seeds with a hash of the frame and the seed (``hash_uint2(frame, seed)``,
    ``BlenderSync::sync_integrator``, ``intern/cycles/blender/sync.cpp``), so both views of a
    frame share a seed and the frames differ.

Under ``multiview`` one render gives both eyes from one ``cycles.seed``, so both views ask for
the same sampler seed (``unset`` or ``animated``); Cycles itself then seeds the second eye
with a hash of the first eye's seed (:func:`integrator_seed`), so the eyes' noise is
independent although one seed was set.
"""

SHARED_SEED_RULES = ("unset", "animated")
"""Seed rules under which both views of a replicate get one seed."""

UNBOUNDED_BOUNCES = 1024
"""Cycles bounce limit standing in for ``render.max_depth: -1``."""

SEED_MODULUS = 2**31
"""``cycles.seed`` holds 0 .. 2^31 - 1."""

MAX_FRAME = 1048574
"""Blender's largest frame number (``MAXFRAME``, the hard maximum of ``scene.frame_current``)."""

ADAPTIVE_STEP = 16
"""Cycles filters (and may stop) adaptively sampled pixels every 16 samples
(``adaptive_sampling.adaptive_step``)."""

COMPOSITOR_GROUP = "stereovar_denoise"
"""Name of the compositor node group of ``denoiser: compositor``."""


def cycles_options(options: dict | None) -> dict:
    """``render.cycles`` with every default filled in."""
    return {**CYCLES_DEFAULTS, **(options or {})}


def _key(name: str) -> str:
    return f"config key 'render.cycles.{name}'"


def _choice_error(opts: dict, name: str, choices) -> str | None:
    if opts[name] not in choices:
        return f"{_key(name)}: {opts[name]!r} is not allowed; use one of {', '.join(choices)}"
    return None


def _type_error(opts: dict) -> str | None:
    for name, default in CYCLES_DEFAULTS.items():
        value = opts[name]
        if isinstance(default, bool):
            ok = isinstance(value, bool)
        elif isinstance(default, int):
            ok = isinstance(value, int) and not isinstance(value, bool) and value >= 0
        elif isinstance(default, float):
            ok = (
                isinstance(value, int | float)
                and not isinstance(value, bool)
                and math.isfinite(value)
                and value >= 0
            )
        else:
            continue
        if not ok:
            kind = {bool: "true or false", int: "an integer >= 0", float: "a number >= 0"}
            return f"{_key(name)}: {value!r} is not allowed; set {kind[type(default)]}"
    return None


def cycles_options_error(options: dict | None, *, rfilter: str = "box") -> str | None:
    """Why the ``render.cycles`` options (and ``render.rfilter``) cannot be rendered or would
    not be linear radiance, as one line naming the key and the fix; None when they are fine.

    Examples
    --------
    >>> cycles_options_error({"denoise": True, "adaptive_sampling": True}) is None
    True
    >>> cycles_options_error({"multiview": True})  # doctest: +ELLIPSIS
    "config key 'render.cycles.multiview': true renders both eyes in one render from ...
    """
    unknown = sorted(set(options or {}) - set(CYCLES_DEFAULTS))
    if unknown:
        return (
            f"{_key(unknown[0])} is not a Cycles setting here; use one of "
            f"{', '.join(CYCLES_DEFAULTS)}"
        )
    opts = cycles_options(options)
    error = _type_error(opts)
    if error:
        return error
    if opts["view_transform"] != "Standard":
        return (
            f"{_key('view_transform')}: {opts['view_transform']!r} is refused; a tone curve "
            "such as Filmic or AgX is not linear radiance and it would quietly change the "
            "per-pixel Monte Carlo variance the experiment measures: set it to Standard"
        )
    if opts["sampling_pattern"] not in SAMPLING_PATTERNS:
        return (
            f"{_key('sampling_pattern')}: {opts['sampling_pattern']!r} is not "
            f"a Cycles pattern; use one of {', '.join(SAMPLING_PATTERNS)}"
        )
    for name, choices in (
        ("denoiser", DENOISERS),
        ("denoising_input_passes", DENOISING_INPUT_PASSES),
        ("seed", SEED_RULES),
    ):
        error = _choice_error(opts, name, choices)
        if error:
            return error
    if opts["multiview"] and opts["seed"] not in SHARED_SEED_RULES:
        return (
            f"{_key('multiview')}: true renders both eyes in one render from one "
            f"cycles.seed, which render.cycles.seed: {opts['seed']} contradicts (a seed per "
            f"view); set render.cycles.seed: {' or '.join(SHARED_SEED_RULES)}, or multiview: "
            "false"
        )
    if rfilter != "box":
        return (
            f"config key 'render.rfilter': {rfilter!r} with render.renderer cycles; the Cycles "
            "renderer uses a box pixel filter one pixel wide so that a pixel's variance is its "
            "own estimator's: set render.rfilter: box"
        )
    return None


def adaptive_min_samples(threshold: float, min_samples: int, spp: int) -> int:
    r"""The minimum number of samples Cycles gives every pixel under adaptive sampling.

    With ``adaptive_min_samples`` 0 Cycles picks the minimum from the threshold
    :math:`t` (itself :math:`\max(0.001, 1/\mathrm{SPP})` when set to 0):

    .. math:: n_\min = \max\bigl(4, \lceil 16 / t^{0.3} \rceil\bigr)

    (threshold 0.1: 32; 0.01: 64; 0.001: 128); a minimum set by hand is raised to 4. Source:
    ``Integrator::get_adaptive_sampling``, ``intern/cycles/scene/integrator.cpp``, lines
    419-429 of Cycles v5.0.0 (``src/scene/integrator.cpp`` of blender/cycles at tag
    v5.0.0, the Cycles of Blender 5.0).

    Examples
    --------
    >>> adaptive_min_samples(0.01, 0, 1024), adaptive_min_samples(0.005, 0, 8192)
    (64, 79)
    >>> adaptive_min_samples(0.01, 2, 128)
    4
    """
    t = float(threshold)
    if t == 0.0 and spp > 0:
        t = max(0.001, 1.0 / float(spp))
    if t > 0 and int(min_samples) == 0:
        return max(4, math.ceil(16.0 / float(t) ** 0.3))
    return max(4, int(min_samples))


def adaptive_first_stop(threshold: float, min_samples: int, spp: int) -> int:
    r"""The number of samples after which Cycles first tests (and may stop) a pixel under
    adaptive sampling: sample index :math:`(n_\min + 1)\,|\,15` is the first filtered one
    (``AdaptiveSampling::align_samples``, ``src/integrator/adaptive_sampling.cpp`` of Cycles
    v5.0.0), so no pixel stops before that many samples plus one. A render of at most this
    many samples is the render without adaptive sampling: at the default threshold 0.01 and
    automatic minimum, 80 SPP or fewer.

    Examples
    --------
    >>> adaptive_first_stop(0.01, 0, 1024)
    80
    """
    n_min = adaptive_min_samples(threshold, min_samples, spp)
    return ((n_min + 1) | (ADAPTIVE_STEP - 1)) + 1


_MASK = 0xFFFFFFFF


def _rot(x: int, k: int) -> int:
    return ((x << k) | (x >> (32 - k))) & _MASK


def hash_uint2(kx: int, ky: int) -> int:
    """Cycles' ``hash_uint2``: the final mix of Bob Jenkins' lookup3 on two 32-bit words
    (``src/util/hash.h`` of Cycles v5.0.0), with which Cycles derives the animated seed and
    the seeds of a multiview render's later views."""
    a = b = c = (0xDEADBEEF + (2 << 2) + 13) & _MASK
    b = (b + ky) & _MASK
    a = (a + kx) & _MASK
    c ^= b
    c = (c - _rot(b, 14)) & _MASK
    a ^= c
    a = (a - _rot(c, 11)) & _MASK
    b ^= a
    b = (b - _rot(a, 25)) & _MASK
    c ^= b
    c = (c - _rot(b, 16)) & _MASK
    a ^= c
    a = (a - _rot(c, 4)) & _MASK
    b ^= a
    b = (b - _rot(a, 14)) & _MASK
    c ^= b
    c = (c - _rot(b, 24)) & _MASK
    return c


def integrator_seed(seed: int, *, animated: bool = False, frame: int = 1, view_index: int = 0):
    r"""The seed Cycles' integrator samples with, from ``cycles.seed`` :math:`s`.

    With ``use_animated_seed`` Blender passes :math:`h(f, s)` for frame :math:`f`
    (``BlenderSync::sync_integrator``, ``intern/cycles/blender/sync.cpp``); view
    :math:`k > 0` of a multiview render then gets :math:`s' + h(s', h(k \cdot
    \mathtt{0xdeadbeef}, 0))` (mod :math:`2^{32}`) from that seed :math:`s'`:
    ``BlenderSession::render`` (``intern/cycles/blender/session.cpp``) "makes sure all views
    have different noise patterns", so the eyes of one multiview render do not share noise.
    :math:`h` is :func:`hash_uint2`.
    """
    s = int(seed) & _MASK
    if animated:
        s = hash_uint2(int(frame) & _MASK, s)
    if view_index:
        s = (s + hash_uint2(s, hash_uint2((int(view_index) * 0xDEADBEEF) & _MASK, 0))) & _MASK
    return s


def seed_policy_of(policy: str, options: dict | None) -> str:
    """The seed policy whose labels a Cycles render's sampler seed comes from: ``shared``
    (both views of a replicate, one seed) under a seed rule of :data:`SHARED_SEED_RULES`,
    else the job's ``policy``."""
    return "shared" if cycles_options(options)["seed"] in SHARED_SEED_RULES else policy


def animated_frame(index) -> int:
    """The frame of replicate ``index`` under the ``animated`` seed rule: ``index + 1``
    (an integer index below :data:`MAX_FRAME`); a label such as ``"preview"`` gets a frame
    hashed from it."""
    if isinstance(index, int) and not isinstance(index, bool):
        if not 0 <= index < MAX_FRAME:
            raise ValueError(
                f"seed index {index} has no Blender frame under render.cycles.seed: animated "
                f"(frames 1 .. {MAX_FRAME}); use fewer seeds or another seed rule"
            )
        return index + 1
    from ...seeding import derive_seed

    return 1 + derive_seed("animated", index) % MAX_FRAME


def sampler_seed(scene: str, view: str, spp, index, *, policy: str, options) -> int:
    """The sampler seed of render ``index`` of ``view`` under ``render.cycles.seed``
    (:data:`SEED_RULES`), as stored with the render: what Cycles is given.

    ``per_view``: :func:`stereovar.seeding.render_seed` under ``policy`` (Cycles gets it mod
    :data:`SEED_MODULUS`, :func:`cycles_seed`); ``unset``: the ``shared`` policy's seed mod
    :data:`SEED_MODULUS`, one per replicate for both views; ``animated``: the frame
    :func:`animated_frame` (``cycles.seed`` is 0).

    Examples
    --------
    >>> a = sampler_seed("s", "left", 4, 0, policy="independent", options={"seed": "unset"})
    >>> b = sampler_seed("s", "right", 4, 0, policy="independent", options={"seed": "unset"})
    >>> a == b, a < 2**31
    (True, True)
    >>> sampler_seed("s", "right", 4, 6, policy="independent", options={"seed": "animated"})
    7
    """
    from ...seeding import render_seed

    rule = cycles_options(options)["seed"]
    if rule == "animated":
        return animated_frame(index)
    seed = render_seed(scene, view, spp, index, policy=seed_policy_of(policy, options))
    return cycles_seed(seed) if rule == "unset" else seed


def bounces(max_depth: int) -> int:
    r"""Cycles' ``max_bounces`` for Mitsuba's ``max_depth``.

    Mitsuba counts path vertices from the camera (``max_depth`` 1: emitters seen directly; 2:
    direct illumination); Cycles counts bounces after the first hit (0: direct illumination):

    .. math:: \mathrm{max\_bounces} = \mathrm{max\_depth} - 2

    (``-1``, unbounded, is :data:`UNBOUNDED_BOUNCES`).
    """
    if max_depth == -1:
        return UNBOUNDED_BOUNCES
    if max_depth < 2:
        raise ValueError(
            "render.max_depth below 2 (emitters only) has no Cycles equivalent; use 2 or more"
        )
    return int(max_depth) - 2


def cycles_seed(seed: int) -> int:
    """``cycles.seed`` of a render seed (:func:`stereovar.seeding.render_seed`, < 2^32)."""
    return int(seed) % SEED_MODULUS


def apply_settings(
    scene, *, spp: int, seed: int, max_depth: int, threads, options, filter_px: float = 1.0
) -> dict:
    """Set every Cycles setting of one render on a ``bpy`` scene and return them as store
    attributes (``cycles_*``); ``filter_px`` narrows the box filter for the geometry render
    only (:func:`.render.render_geometry`).

    ``seed`` is the render's sampler seed (:func:`sampler_seed`): ``cycles.seed`` is it mod
    :data:`SEED_MODULUS`, but under the ``animated`` rule, where it is the frame number
    (wrapped into 1 .. :data:`MAX_FRAME`) and ``cycles.seed`` is 0. The denoiser's compositor
    nodes are built here (:func:`set_denoiser`); the multiview camera is set by
    :func:`.render.render_views`, which reads the flag set here.
    """
    opts = cycles_options(options)
    error = cycles_options_error(opts)
    if error:
        from ...errors import ConfigError

        raise ConfigError(error)
    c = scene.cycles
    scene.render.engine = "CYCLES"
    c.device = "CPU"
    c.samples = int(spp)
    if opts["seed"] == "animated":
        c.seed = 0
        c.use_animated_seed = True
        scene.frame_current = 1 + (int(seed) - 1) % MAX_FRAME
    else:
        c.seed = cycles_seed(seed)
        c.use_animated_seed = False
        scene.frame_current = 1
    c.sampling_pattern = opts["sampling_pattern"]
    c.use_adaptive_sampling = bool(opts["adaptive_sampling"])
    c.adaptive_threshold = float(opts["adaptive_threshold"])
    c.adaptive_min_samples = int(opts["adaptive_min_samples"])
    c.time_limit = 0.0
    denoiser = set_denoiser(scene, opts)
    c.use_light_tree = bool(opts["light_tree"])
    c.sample_clamp_direct = float(opts["clamp_direct"])
    c.sample_clamp_indirect = float(opts["clamp_indirect"])
    n = bounces(max_depth)
    c.max_bounces = n
    for key in ("diffuse_bounces", "glossy_bounces", "transmission_bounces"):
        setattr(c, key, n)
    c.volume_bounces = 0
    c.transparent_max_bounces = n
    c.min_light_bounces = 0
    c.min_transparent_bounces = 0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.blur_glossy = 0.0
    c.use_guiding = False
    c.pixel_filter_type = "BOX"
    c.filter_width = float(filter_px)
    scene.render.filter_size = float(filter_px)
    scene.render.use_multiview = bool(opts["multiview"])
    scene.render.views_format = "STEREO_3D"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.film_transparent = False
    if threads:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = int(threads)
    else:
        scene.render.threads_mode = "AUTO"
    adaptive = {}
    if c.use_adaptive_sampling:
        args = (c.adaptive_threshold, c.adaptive_min_samples, c.samples)
        adaptive = {
            "cycles_adaptive_min_samples_used": adaptive_min_samples(*args),
            "cycles_adaptive_first_stop": adaptive_first_stop(*args),
        }
    return {
        "cycles_device": c.device,
        "cycles_seed_rule": opts["seed"],
        "cycles_seed": int(c.seed),
        "cycles_animated_seed": bool(c.use_animated_seed),
        "cycles_frame": int(scene.frame_current),
        "cycles_integrator_seed": integrator_seed(
            c.seed, animated=c.use_animated_seed, frame=scene.frame_current
        ),
        "cycles_sampling_pattern": c.sampling_pattern,
        "cycles_adaptive_sampling": bool(c.use_adaptive_sampling),
        "cycles_adaptive_threshold": float(c.adaptive_threshold),
        "cycles_adaptive_min_samples": int(c.adaptive_min_samples),
        **adaptive,
        **denoiser,
        "cycles_multiview": bool(scene.render.use_multiview),
        "cycles_light_tree": bool(c.use_light_tree),
        "cycles_clamp_direct": float(c.sample_clamp_direct),
        "cycles_clamp_indirect": float(c.sample_clamp_indirect),
        "cycles_max_bounces": int(c.max_bounces),
        "cycles_pixel_filter": f"{c.pixel_filter_type} {c.filter_width:g} px",
        "cycles_view_transform": scene.view_settings.view_transform,
        "cycles_threads": int(scene.render.threads),
    }


def set_denoiser(scene, opts: dict) -> dict:
    """Turn Cycles' OIDN denoiser on where ``opts`` say (:data:`DENOISERS`), off elsewhere,
    and return it as store attributes.

    Off: ``use_denoising`` off, no compositor node group, no guide passes. ``render``: the
    render settings' OIDN on the CPU with ``denoising_input_passes`` and Blender's default
    prefilter (Accurate) and quality (High). ``compositor``: Cycles' denoiser off, and a
    compositor node group Render Layers → Denoise → Group Output with the Diffuse Color and
    Normal passes linked to the Albedo and Normal inputs as ``denoising_input_passes`` asks
    (:func:`compositor_denoiser`).
    """
    c = scene.cycles
    layer = scene.view_layers[0]
    on = bool(opts["denoise"])
    mode = opts["denoiser"] if on else "none"
    passes = opts["denoising_input_passes"]
    c.use_denoising = mode == "render"
    layer.cycles.use_denoising = True
    layer.cycles.denoising_store_passes = False
    c.denoiser = "OPENIMAGEDENOISE"
    c.denoising_input_passes = passes
    c.denoising_prefilter = "ACCURATE"
    c.denoising_quality = "HIGH"
    c.denoising_use_gpu = False
    layer.use_pass_diffuse_color = mode == "compositor" and passes != "RGB"
    layer.use_pass_normal = mode == "compositor" and passes == "RGB_ALBEDO_NORMAL"
    attrs = {
        "cycles_denoise": on,
        "cycles_denoiser": mode,
        "cycles_denoising_input_passes": passes,
    }
    if mode == "compositor":
        scene.compositing_node_group = compositor_denoiser(scene, passes)
        scene.render.use_compositing = True
        node = scene.compositing_node_group.nodes["Denoise"]
        attrs["cycles_compositor_denoise"] = ", ".join(
            f"{name} {node.inputs[name].default_value}" for name in ("HDR", "Prefilter", "Quality")
        )
    else:
        scene.compositing_node_group = None
        if mode == "render":
            attrs["cycles_render_denoise"] = (
                f"{c.denoiser} prefilter {c.denoising_prefilter} quality {c.denoising_quality}"
            )
    return attrs


def compositor_denoiser(scene, passes: str):
    """The compositor node group of ``denoiser: compositor`` (Blender 5's
    ``scene.compositing_node_group``): the render layer's Image through a Denoise node
    (Blender's defaults) to the group output, Diffuse Color to its Albedo input unless
    ``passes`` is ``RGB``, Normal to its Normal input for ``RGB_ALBEDO_NORMAL``. Rebuilt on
    every call, so it always matches ``passes``."""
    import bpy

    old = bpy.data.node_groups.get(COMPOSITOR_GROUP)
    if old is not None:
        bpy.data.node_groups.remove(old)
    group = bpy.data.node_groups.new(COMPOSITOR_GROUP, "CompositorNodeTree")
    group.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    layers = group.nodes.new("CompositorNodeRLayers")
    layers.scene = scene
    layers.layer = scene.view_layers[0].name
    denoise = group.nodes.new("CompositorNodeDenoise")
    denoise.name = "Denoise"
    out = group.nodes.new("NodeGroupOutput")
    group.links.new(layers.outputs["Image"], denoise.inputs["Image"])
    if passes != "RGB":
        group.links.new(layers.outputs["Diffuse Color"], denoise.inputs["Albedo"])
    if passes == "RGB_ALBEDO_NORMAL":
        group.links.new(layers.outputs["Normal"], denoise.inputs["Normal"])
    group.links.new(denoise.outputs["Image"], out.inputs[0])
    return group
