"""Path-traced Cycles renders of one view of the rig, with an explicit seed, read back as
linear float radiance (and, for the geometry checks, the Depth and IndexOB passes)."""

from __future__ import annotations

import os
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ...rig import StereoRig
from .scene import camera_matrix
from .settings import apply_settings


@contextmanager
def _quiet():
    """Send Blender's per-render lines on the C-level stdout to /dev/null."""
    sys.stdout.flush()
    saved = os.dup(1)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)
        os.close(devnull)


def _read_layers(path) -> dict:
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        return {name: np.asarray(ch.pixels) for name, ch in f.channels().items()}


def _channel(channels: dict, suffix: str) -> np.ndarray:
    for name, pixels in channels.items():
        if name.endswith(suffix):
            return pixels
    raise RuntimeError(f"Cycles wrote no '{suffix}' channel (has {', '.join(channels)})")


def render_view(
    bpy,
    camera,
    rig: StereoRig,
    view: str,
    *,
    spp: int,
    seed: int,
    max_depth: int,
    threads=None,
    options=None,
    passes: bool = False,
):
    """Render one view of the rig with Cycles.

    Parameters
    ----------
    bpy : module
    camera : bpy.types.Object
        The scene camera (:func:`.scene.build_scene`), moved to ``view``.
    rig : StereoRig
    view : {"left", "right"}
    spp, seed, max_depth : int
        Samples per pixel, the render seed (:func:`stereovar.seeding.render_seed`) and
        Mitsuba's path depth (:func:`.settings.bounces`).
    threads : int, optional
    options : dict, optional
        ``render.cycles`` (:data:`.settings.CYCLES_DEFAULTS`).
    passes : bool
        Also return the Depth (planar, m) and IndexOB passes.

    Returns
    -------
    image : numpy.ndarray, float32 (H, W, 3)
        Linear RGB radiance.
    attrs : dict
        The settings used (:func:`.settings.apply_settings`).
    extra : dict
        ``depth`` and ``object_index`` (H, W) when ``passes``.
    """
    import mathutils

    scene = bpy.context.scene
    camera.matrix_world = mathutils.Matrix(camera_matrix(rig.to_world[view]).tolist())
    attrs = apply_settings(
        scene, spp=spp, seed=seed, max_depth=max_depth, threads=threads, options=options
    )
    layer = scene.view_layers[0]
    layer.use_pass_combined = True
    layer.use_pass_z = passes
    layer.use_pass_object_index = passes
    settings = scene.render.image_settings
    settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "NONE"
    with tempfile.TemporaryDirectory(prefix="stereovar-cycles-") as tmp:
        path = Path(tmp) / "render.exr"
        scene.render.filepath = str(path)
        with _quiet():
            bpy.ops.render.render(write_still=True)
        channels = _read_layers(path)
    image = np.stack([_channel(channels, f"Combined.{c}") for c in "RGB"], axis=-1)
    extra = {}
    if passes:
        extra["depth"] = _channel(channels, "Depth.Z").astype(np.float64)
        extra["object_index"] = np.rint(_channel(channels, "IndexOB.X")).astype(np.int32)
    return image.astype(np.float32), attrs, extra
