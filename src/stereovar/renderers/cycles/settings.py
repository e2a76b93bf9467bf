"""Cycles render settings that keep the experiment honest, each set explicitly and recorded.

Every render sets, and records in its store's provenance: path tracing on the CPU device;
``cycles.seed`` from the seed policy; the denoiser, adaptive sampling, the light tree and
clamping off (unless ``render.cycles`` turns the light tree or clamping on, which is
recorded); the bounce limits from ``render.max_depth``; a box pixel filter one pixel wide; the
Standard view transform with linear float output; the job's thread count.

The denoiser, adaptive sampling and any view transform but Standard would quietly change the
per-pixel variance the paper measures, so :func:`cycles_options_error` refuses them.
"""

from __future__ import annotations

CYCLES_DEFAULTS = {
    "denoise": False,
    "adaptive_sampling": False,
    "view_transform": "Standard",
    "light_tree": False,
    "clamp_direct": 0.0,
    "clamp_indirect": 0.0,
    "sampling_pattern": "TABULATED_SOBOL",
}
"""``render.cycles`` options and their defaults."""

SAMPLING_PATTERNS = ("TABULATED_SOBOL", "BLUE_NOISE")
"""Cycles' sample patterns (it has no independent sampler; the seed scrambles the pattern)."""

UNBOUNDED_BOUNCES = 1024
"""Cycles bounce limit standing in for ``render.max_depth: -1``."""

SEED_MODULUS = 2**31
"""``cycles.seed`` holds 0 .. 2^31 - 1."""


def cycles_options(options: dict | None) -> dict:
    """``render.cycles`` with every default filled in."""
    return {**CYCLES_DEFAULTS, **(options or {})}


def cycles_options_error(options: dict | None, *, rfilter: str = "box") -> str | None:
    """Why the ``render.cycles`` options (and ``render.rfilter``) would bias the measurement,
    as one line naming the key and the fix; None when they are honest."""
    opts = cycles_options(options)
    why = "it would quietly change the per-pixel Monte Carlo variance the experiment measures"
    if opts["denoise"]:
        return f"config key 'render.cycles.denoise': true is refused; {why}: set it to false"
    if opts["adaptive_sampling"]:
        return (
            f"config key 'render.cycles.adaptive_sampling': true is refused; {why} (pixels "
            "would stop at different sample counts): set it to false"
        )
    if opts["view_transform"] != "Standard":
        return (
            f"config key 'render.cycles.view_transform': {opts['view_transform']!r} is refused; "
            f"a tone curve such as Filmic or AgX is not linear radiance and {why}: set it to "
            "Standard"
        )
    if opts["sampling_pattern"] not in SAMPLING_PATTERNS:
        return (
            f"config key 'render.cycles.sampling_pattern': {opts['sampling_pattern']!r} is not "
            f"a Cycles pattern; use one of {', '.join(SAMPLING_PATTERNS)}"
        )
    if rfilter != "box":
        return (
            f"config key 'render.rfilter': {rfilter!r} with render.renderer cycles; the Cycles "
            "renderer uses a box pixel filter one pixel wide so that a pixel's variance is its "
            "own estimator's: set render.rfilter: box"
        )
    return None


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
    only (:func:`.render.render_geometry`)."""
    opts = cycles_options(options)
    error = cycles_options_error(opts)
    if error:
        from ...errors import ConfigError

        raise ConfigError(error)
    c = scene.cycles
    scene.render.engine = "CYCLES"
    c.device = "CPU"
    c.samples = int(spp)
    c.seed = cycles_seed(seed)
    c.use_animated_seed = False
    c.sampling_pattern = opts["sampling_pattern"]
    c.use_adaptive_sampling = False
    c.time_limit = 0.0
    c.use_denoising = False
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
    return {
        "cycles_device": c.device,
        "cycles_seed": int(c.seed),
        "cycles_sampling_pattern": c.sampling_pattern,
        "cycles_denoise": bool(c.use_denoising),
        "cycles_adaptive_sampling": bool(c.use_adaptive_sampling),
        "cycles_light_tree": bool(c.use_light_tree),
        "cycles_clamp_direct": float(c.sample_clamp_direct),
        "cycles_clamp_indirect": float(c.sample_clamp_indirect),
        "cycles_max_bounces": int(c.max_bounces),
        "cycles_pixel_filter": f"{c.pixel_filter_type} {c.filter_width:g} px",
        "cycles_view_transform": scene.view_settings.view_transform,
        "cycles_threads": int(scene.render.threads),
    }
