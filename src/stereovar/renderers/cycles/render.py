"""Path-traced Cycles renders of one view of the rig, with an explicit seed, read back as
linear float radiance; and Cycles' own first hits of the pixel-centre rays (planar depth and
object index), which the geometry checks compare with the renderer-neutral ground truth."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from ...io.images import read_image
from ...rig import StereoRig
from ..quiet import silenced
from .scene import camera_matrix
from .settings import apply_settings


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
    filter_px: float = 1.0,
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
    filter_px : float
        Box pixel filter width (1: a pixel's variance is its own estimator's).

    Returns
    -------
    image : numpy.ndarray, float32 (H, W, 3)
        Linear RGB radiance.
    attrs : dict
        The settings used (:func:`.settings.apply_settings`).
    """
    import mathutils

    scene = bpy.context.scene
    camera.matrix_world = mathutils.Matrix(camera_matrix(rig.to_world[view]).tolist())
    attrs = apply_settings(
        scene,
        spp=spp,
        seed=seed,
        max_depth=max_depth,
        threads=threads,
        options=options,
        filter_px=filter_px,
    )
    settings = scene.render.image_settings
    settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "NONE"
    with tempfile.TemporaryDirectory(prefix="stereovar-cycles-") as tmp:
        path = Path(tmp) / "render.exr"
        scene.render.filepath = str(path)
        with silenced(1):  # Blender's per-render lines
            bpy.ops.render.render(write_still=True)
        image = read_image(path)  # the Combined layer, linear float32
    return image, attrs


GEOMETRY_FILTER_PX = 0.01
"""Pixel filter width of :func:`render_geometry`: every sample at the pixel centre."""


def _geometry_material(bpy):
    """Emission of (planar depth, pass index, 0) at the first hit: Cycles' own geometry."""
    mat = bpy.data.materials.get("stereovar_geometry")
    if mat is not None:
        return mat
    mat = bpy.data.materials.new("stereovar_geometry")
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Strength"].default_value = 1.0
    camera = nodes.new("ShaderNodeCameraData")
    info = nodes.new("ShaderNodeObjectInfo")
    combine = nodes.new("ShaderNodeCombineXYZ")
    links.new(camera.outputs["View Z Depth"], combine.inputs["X"])
    links.new(info.outputs["Object Index"], combine.inputs["Y"])
    links.new(combine.outputs["Vector"], emission.inputs["Color"])
    links.new(emission.outputs["Emission"], output.inputs["Surface"])
    return mat


def render_geometry(bpy, camera, rig: StereoRig, view: str, *, threads=None) -> dict:
    """Cycles' own first hits of the pixel-centre rays of ``view``: ``depth`` (planar, m; 0
    where nothing is hit) and ``object_index`` (the pass index, 0 for the background).

    Every object is rendered with one emission material whose colour is (View Z Depth,
    Object Index, 0), with no bounce, one sample per pixel and a
    :data:`GEOMETRY_FILTER_PX`-wide pixel filter, so each pixel holds the values at the
    first hit of its centre ray. The scene's materials are restored afterwards (and the next
    render sets its own filter).
    """
    scene = bpy.context.scene
    layer = scene.view_layers[0]
    saved = layer.material_override
    layer.material_override = _geometry_material(bpy)
    try:
        image, _ = render_view(
            bpy,
            camera,
            rig,
            view,
            spp=1,
            seed=0,
            max_depth=2,
            threads=threads,
            filter_px=GEOMETRY_FILTER_PX,
        )
    finally:
        layer.material_override = saved
    return {
        "depth": image[..., 0].astype(np.float64),
        "object_index": np.rint(image[..., 1]).astype(np.int32),
    }
