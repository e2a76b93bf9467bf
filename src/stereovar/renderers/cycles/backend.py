"""Load Blender's ``bpy`` module (the optional ``cycles`` extra) in one place.

Nothing else in the package imports ``bpy``: call :func:`load_bpy`. Importing this module
pulls in no third-party package.
"""

from __future__ import annotations

import sys

from ...errors import BackendError

EXTRA_HINT = (
    "install Blender's Python module with pip install -e '.[cycles]' (bpy 5.0 wheels exist "
    "for CPython 3.11 only), or set render.renderer: mitsuba"
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


def describe_backend() -> dict:
    """Blender's version and the Cycles device, as provenance strings."""
    bpy = load_bpy()
    return {
        "renderer": "cycles",
        "renderer_version": bpy.app.version_string,
        "variant": "cpu",
        "blender_build_hash": bpy.app.build_hash.decode()
        if isinstance(bpy.app.build_hash, bytes)
        else str(bpy.app.build_hash),
    }
