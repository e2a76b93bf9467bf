"""Load Blender's ``bpy`` module (the optional ``cycles`` extra) in one place.

Nothing else in the package imports ``bpy``: call :func:`load_bpy`. Importing this module
pulls in no third-party package.
"""

from __future__ import annotations

import sys

from ...errors import BackendError

EXTRA_HINT = (
    "install Blender's Python module with pip install 'stereovar[cycles]' (in a checkout, "
    "make setup does; bpy 5.0 wheels exist for CPython 3.11 only), or set render.renderer: "
    "mitsuba"
)


def load_bpy():
    """Import ``bpy`` and return it.

    Raises
    ------
    BackendError
        ``bpy`` is not installed or cannot be imported here (one line naming the extra).
    """
    try:
        import bpy
    except ImportError as err:
        here = f"Python {sys.version_info.major}.{sys.version_info.minor}"
        raise BackendError(
            f"render.renderer: cycles needs the bpy module, which is not importable on {here} "
            f"({' '.join(str(err).split())[:120]}); {EXTRA_HINT}"
        ) from None
    return bpy


FIXED_SETTINGS = {
    "cycles_device": "CPU",
    "cycles_integrator": "path tracing",
    "cycles_pixel_filter": "BOX 1 px",
    "cycles_view_transform": "Standard",
    "cycles_output": "linear float32 OpenEXR",
    "cycles_bounces": "max_bounces = max_depth - 2 (diffuse, glossy, transmission alike)",
    "cycles_seed_rule": (
        "render.cycles.seed per_view: cycles.seed = sampler seed mod 2^31, a seed per view; "
        "unset: the same, one sampler seed per replicate shared by both views; animated: "
        "cycles.seed 0, use_animated_seed, frame = sampler seed = replicate index + 1"
    ),
}
"""Render settings every Cycles render uses whatever the config says
(:func:`.settings.apply_settings`), recorded in every store's provenance."""


def describe_backend() -> dict:
    """Blender's version, the Cycles device and :data:`FIXED_SETTINGS`, as provenance
    strings."""
    bpy = load_bpy()
    build = bpy.app.build_hash
    return {
        "renderer": "cycles",
        "renderer_version": bpy.app.version_string,
        "variant": "cpu",
        "jit_target": "",
        "blender_build_hash": build.decode() if isinstance(build, bytes) else str(build),
        **FIXED_SETTINGS,
    }
