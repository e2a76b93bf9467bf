"""Path-traced Cycles renders of the rig's views, with an explicit seed, read back as linear
float radiance; and Cycles' own first hits of the pixel-centre rays (planar depth and object
index), which the geometry checks compare with the renderer-neutral ground truth.

A render is one view (:func:`render_view`) or, under ``render.cycles.multiview``, both views
in one Blender multiview render from one ``cycles.seed`` (:func:`render_pair`), the camera's
stereo settings placing the two eyes exactly at the rig's poses (:func:`multiview_rig`).
Cycles seeds the second eye with a hash of the first eye's seed
(:func:`.settings.integrator_seed`), so the eyes of a multiview render have independent
noise.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ...io.images import read_image
from ...rig import VIEWS, StereoRig
from ..quiet import silenced
from .scene import camera_matrix
from .settings import apply_settings, cycles_options, integrator_seed

LAYERS = {"compositor": "Composite.Combined"}
"""The multilayer EXR layer holding the image, by denoiser (``ViewLayer.Combined``, the
render, unless the compositor made it)."""


class MultiviewRig(NamedTuple):
    """How Blender's stereo camera (parallel convergence) reproduces a rig.

    Attributes
    ----------
    to_world : numpy.ndarray, (4, 4)
        The camera object's pose (Mitsuba's camera convention): the rig's left view.
    pivot : {"LEFT", "RIGHT"}
        Which of Blender's eyes sits at the camera object.
    interocular_m : float
        Blender's interocular distance: the baseline.
    eyes : dict of str to str
        Blender's eye (``left``, ``right``) of each rig view.
    """

    to_world: np.ndarray
    pivot: str
    interocular_m: float
    eyes: dict


def multiview_rig(rig: StereoRig) -> MultiviewRig:
    r"""Blender's stereo camera settings whose two eyes are the rig's two views.

    With parallel convergence Blender places its right eye at the left eye moved by the
    interocular distance :math:`B` along the camera's x axis, Blender's image-right
    :math:`\hat{x}_B = -\hat{x}_L` (:math:`\hat{x}_L` the Mitsuba image-left axis of
    :func:`stereovar.rig.make_rig`), with no shift and the same orientation. So

    .. math:: O_R - O_L = s\,B\,\hat{x}_L = -s\,B\,\hat{x}_B

    is Blender's right eye for ``conventional`` (:math:`s = -1`; pivot ``LEFT``: the camera
    object is the left eye) and Blender's left eye for ``paper`` (:math:`s = +1`; pivot
    ``RIGHT``, the camera object at the rig's left view, which is then Blender's right eye).
    Either way the camera object sits at the rig's left pose and the other eye at its right
    pose, exactly (to Blender's float32 interocular distance).

    Raises
    ------
    stereovar.errors.ConfigError
        The views differ by more than a translation along the camera's x axis, which a
        stereo camera cannot express (one line).
    """
    from ...errors import ConfigError

    left = np.asarray(rig.to_world["left"], dtype=np.float64)
    right = np.asarray(rig.to_world["right"], dtype=np.float64)
    x_blender = -left[:3, 0] / np.linalg.norm(left[:3, 0])
    offset = right[:3, 3] - left[:3, 3]
    along = float(offset @ x_blender)
    scale = max(1.0, float(np.abs(left[:3, 3]).max()))
    if (
        not np.allclose(left[:3, :3], right[:3, :3], rtol=0.0, atol=1e-12)
        or np.abs(offset - along * x_blender).max() > 1e-12 * scale
        or along == 0.0
    ):
        raise ConfigError(
            "config key 'render.cycles.multiview': true needs the right view to be the left "
            "one moved along its image x axis (Blender's stereo camera), and this rig's is "
            "not: set render.cycles.multiview: false"
        )
    if along > 0:
        return MultiviewRig(left.copy(), "LEFT", along, {"left": "left", "right": "right"})
    return MultiviewRig(left.copy(), "RIGHT", -along, {"left": "right", "right": "left"})


def _place(camera, to_world) -> None:
    import mathutils

    camera.matrix_world = mathutils.Matrix(camera_matrix(to_world).tolist())


def _render_exr(bpy, attrs: dict, views=None) -> dict:
    """Render the scene as it is set and read each written view back as linear float RGB:
    ``{None: image}``, or ``{eye: image}`` for Blender's multiview ``views``."""
    scene = bpy.context.scene
    settings = scene.render.image_settings
    settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "NONE"
    settings.views_format = "INDIVIDUAL"
    layer = LAYERS.get(attrs.get("cycles_denoiser"), "ViewLayer.Combined")
    with tempfile.TemporaryDirectory(prefix="stereovar-cycles-") as tmp:
        path = Path(tmp) / "render.exr"
        scene.render.filepath = str(path)
        with silenced(1):  # Blender's per-render lines
            bpy.ops.render.render(write_still=True)
        if views is None:
            return {None: read_image(path, channel=layer)}
        return {
            eye: read_image(
                path.with_name(f"render{scene.render.views[eye].file_suffix}.exr"),
                channel=layer,
            )
            for eye in views
        }


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
        Samples per pixel, the sampler seed (:func:`.settings.sampler_seed`) and Mitsuba's
        path depth (:func:`.settings.bounces`).
    threads : int, optional
    options : dict, optional
        ``render.cycles`` (:data:`.settings.CYCLES_DEFAULTS`). With ``multiview`` both views
        are rendered (:func:`render_pair`) and ``view`` returned.
    filter_px : float
        Box pixel filter width (1: a pixel's variance is its own estimator's).

    Returns
    -------
    image : numpy.ndarray, float32 (H, W, 3)
        Linear RGB radiance (the composite of the compositor denoiser).
    attrs : dict
        The settings used (:func:`.settings.apply_settings`).
    """
    kwargs = dict(spp=spp, seed=seed, max_depth=max_depth, threads=threads, options=options)
    if cycles_options(options)["multiview"]:
        images, attrs = render_pair(bpy, camera, rig, filter_px=filter_px, **kwargs)
        return images[view], attrs
    scene = bpy.context.scene
    _place(camera, rig.to_world[view])
    attrs = apply_settings(scene, filter_px=filter_px, **kwargs)
    return _render_exr(bpy, attrs)[None], attrs


def render_pair(
    bpy,
    camera,
    rig: StereoRig,
    *,
    spp: int,
    seed: int,
    max_depth: int,
    threads=None,
    options=None,
    filter_px: float = 1.0,
):
    """Render both views of the rig in one Blender multiview render (``STEREO_3D``, parallel
    convergence, :func:`multiview_rig`) from one ``cycles.seed``, as BlenderProc renders
    stereo. Blender's first eye samples with that seed, the second with the seed Cycles
    derives from it (:func:`.settings.integrator_seed`; both recorded as
    ``cycles_integrator_seeds``).

    Parameters are those of :func:`render_view`; ``options`` must have ``multiview`` on.

    Returns
    -------
    images : dict of str to numpy.ndarray
        ``left`` and ``right``, float32 (H, W, 3) linear RGB.
    attrs : dict
        The settings used, with the stereo camera's (``cycles_multiview_*``).
    """
    scene = bpy.context.scene
    attrs = apply_settings(
        scene,
        spp=spp,
        seed=seed,
        max_depth=max_depth,
        threads=threads,
        options=options,
        filter_px=filter_px,
    )
    if not scene.render.use_multiview:
        raise ValueError("render_pair needs render.cycles.multiview: true")
    stereo, camera_attrs = set_stereo_camera(scene, camera, rig)
    attrs.update(camera_attrs)
    images = _render_exr(bpy, attrs, views=VIEWS)
    return {view: images[stereo.eyes[view]] for view in VIEWS}, attrs


def set_stereo_camera(scene, camera, rig: StereoRig):
    """Place ``camera`` and set its stereo settings so that Blender's two eyes are the rig's
    views (:func:`multiview_rig`), both eyes rendered; returns the :class:`MultiviewRig` and
    the settings as store attributes, with the integrator seed of each view
    (:func:`.settings.integrator_seed`: Cycles renders the eyes in the order of
    ``scene.render.views`` and re-seeds every one after the first)."""
    stereo = multiview_rig(rig)
    _place(camera, stereo.to_world)
    cam = camera.data
    cam.stereo.convergence_mode = "PARALLEL"
    cam.stereo.use_spherical_stereo = False
    cam.stereo.pivot = stereo.pivot
    cam.stereo.interocular_distance = stereo.interocular_m
    for eye in VIEWS:
        scene.render.views[eye].use = True
    order = [v.name for v in scene.render.views if v.use]
    c = scene.cycles
    eye_seeds = {
        eye: integrator_seed(
            c.seed, animated=c.use_animated_seed, frame=scene.frame_current, view_index=k
        )
        for k, eye in enumerate(order)
    }
    return stereo, {
        "cycles_multiview_pivot": cam.stereo.pivot,
        "cycles_multiview_convergence": cam.stereo.convergence_mode,
        "cycles_multiview_interocular_m": float(cam.stereo.interocular_distance),
        "cycles_multiview_eyes": ", ".join(f"{v}={stereo.eyes[v]}" for v in VIEWS),
        "cycles_integrator_seeds": ", ".join(f"{v}={eye_seeds[stereo.eyes[v]]}" for v in VIEWS),
    }


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
