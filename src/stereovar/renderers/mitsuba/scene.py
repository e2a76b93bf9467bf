"""Compile renderer-neutral scene specs into Mitsuba 3 scenes.

A spec (see ``schemas/scene.schema.yaml`` and :mod:`stereovar.scenes.spec`) is either procedural
(camera, textures, materials, objects, lights) or points at a user's Mitsuba XML file. Both
compile to a :class:`mitsuba.Scene` without sensors; the stereo rig's sensors are built
separately by :mod:`stereovar.rig` and passed to ``mi.render`` explicitly, so the same scene
object serves both views and the ground-truth tracer.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ...errors import SceneError
from ...geometry import camera_frame, object_matrix


@dataclass(frozen=True)
class Camera:
    """The scene's (left) camera.

    Attributes
    ----------
    to_world : numpy.ndarray, shape (4, 4)
        Camera-to-world matrix; its first three columns are the camera axes x (image left),
        y (up) and z (forward), as Mitsuba's ``look_at`` builds them.
    fov_deg : float
        Horizontal field of view in degrees.
    """

    to_world: np.ndarray
    fov_deg: float


def camera_from_spec(spec: dict) -> Camera:
    """Left camera of a procedural spec (``camera`` block: origin, target, up, fov_deg)."""
    cam = spec["camera"]
    try:
        frame = camera_frame(cam["origin"], cam["target"], cam.get("up", (0.0, 1.0, 0.0)))
    except ValueError as err:
        raise SceneError(f"scene '{spec['name']}': camera: {err}") from None
    to_world = np.eye(4)
    to_world[:3, :3] = frame.T
    to_world[:3, 3] = cam["origin"]
    return Camera(to_world=to_world, fov_deg=float(cam.get("fov_deg", 60.0)))


def lathe_mesh(profile, segments: int) -> tuple[np.ndarray, np.ndarray]:
    """Closed triangle mesh of a solid of revolution about the local +y axis.

    Parameters
    ----------
    profile : array_like, shape (n, 2)
        Points ``(r, y)`` from bottom to top, ``r >= 0``. The ends are closed by flat caps
        where their radius is positive.
    segments : int
        Number of angular subdivisions.

    Returns
    -------
    vertices : numpy.ndarray, shape (V, 3), float64
    faces : numpy.ndarray, shape (F, 3), uint32
        Counter-clockwise seen from outside, so normals point outwards. Caps use their own
        vertices so that smoothed normals do not bend across the rim.
    """
    prof = np.asarray(profile, dtype=np.float64)
    if prof.ndim != 2 or prof.shape[1] != 2 or len(prof) < 2 or np.any(prof[:, 0] < 0):
        raise ValueError("lathe profile must be >= 2 points [r, y] with r >= 0")
    if np.any(np.diff(prof[:, 1]) <= 0):
        raise ValueError("lathe profile heights y must increase strictly from bottom to top")
    theta = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    n = len(prof)
    ring = np.stack(
        [
            prof[:, :1] * np.cos(theta)[None, :],
            np.repeat(prof[:, 1:2], segments, 1),
            prof[:, :1] * np.sin(theta)[None, :],
        ],
        axis=-1,
    ).reshape(-1, 3)
    idx = np.arange(n * segments).reshape(n, segments)
    nxt = np.roll(idx, -1, axis=1)
    # Side quads (a, b) on ring i, (c, d) on ring i + 1: (a, c, b) and (b, c, d) face outwards
    # because y increases with i.
    faces = [
        np.stack([idx[:-1], idx[1:], nxt[:-1]], -1),
        np.stack([nxt[:-1], idx[1:], nxt[1:]], -1),
    ]
    vertices = [ring]
    offset = len(ring)
    for end, facing_down in ((0, True), (n - 1, False)):
        r, y = prof[end]
        if r <= 0:
            continue
        vertices.append(np.concatenate([[[0.0, y, 0.0]], ring[idx[end]]]))
        rim = offset + 1 + np.arange(segments)
        rim_next = np.roll(rim, -1)
        pair = (rim, rim_next) if facing_down else (rim_next, rim)
        faces.append(np.stack([np.full(segments, offset), *pair], -1))
        offset += segments + 1
    v = np.concatenate(vertices)
    f = np.concatenate([x.reshape(-1, 3) for x in faces])
    tri = v[f]
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    f = f[area > 1e-12]
    return v, f.astype(np.uint32)


@lru_cache(maxsize=64)
def baked_texture(texture_json: str) -> np.ndarray:
    """The baked bitmap of a texture spec given as sorted JSON (cached per process; both
    renderers' compilers read it)."""
    from ...scenes.textures import bake_texture_cached

    return bake_texture_cached(json.loads(texture_json))


def _rgb(value):
    return {"type": "rgb", "value": [float(c) for c in value]}


def _texture_dict(mi, spec: dict, name: str) -> dict:
    tex = spec["textures"][name]
    image = baked_texture(json.dumps(tex, sort_keys=True))
    su, sv = tex.get("repeat", (1.0, 1.0))
    return {
        "type": "bitmap",
        # A private copy: the bitmap must not share memory with the cached bake.
        "bitmap": mi.Bitmap(np.array(image, dtype=np.float32, order="C", copy=True)),
        "raw": True,
        "filter_type": "bilinear",
        "wrap_mode": "repeat",
        "to_uv": mi.ScalarTransform4f().scale([float(su), float(sv), 1.0]),
    }


def material_dict(mi, spec: dict, name: str) -> dict:
    """Mitsuba BSDF dict of material ``name`` of ``spec``.

    ``diffuse`` → ``diffuse``; ``glossy`` → ``plastic``/``roughplastic``; ``conductor`` →
    ``conductor``/``roughconductor``; ``glass`` → ``dielectric``/``roughdielectric``
    (rough variants when ``roughness > 0``, with ``alpha = roughness``).
    """
    mat = spec["materials"][name]
    kind = mat["type"]
    rough = float(mat.get("roughness", 0.0))
    if kind == "diffuse":
        albedo = (
            _texture_dict(mi, spec, mat["texture"])
            if "texture" in mat
            else _rgb(mat["reflectance"])
        )
        return {"type": "diffuse", "reflectance": albedo}
    if kind == "glossy":
        albedo = (
            _texture_dict(mi, spec, mat["texture"])
            if "texture" in mat
            else _rgb(mat["reflectance"])
        )
        out = {"diffuse_reflectance": albedo, "int_ior": float(mat.get("ior", 1.49))}
        if rough > 0:
            return {"type": "roughplastic", "alpha": rough, **out}
        return {"type": "plastic", **out}
    if kind == "conductor":
        if rough > 0:
            return {"type": "roughconductor", "material": mat["metal"], "alpha": rough}
        return {"type": "conductor", "material": mat["metal"]}
    if kind == "glass":
        out = {
            "int_ior": float(mat.get("ior", 1.5)),
            "ext_ior": 1.000277,
            "specular_transmittance": _rgb(mat.get("tint", (1.0, 1.0, 1.0))),
        }
        if rough > 0:
            return {"type": "roughdielectric", "alpha": rough, **out}
        return {"type": "dielectric", **out}
    raise SceneError(f"scene '{spec['name']}': material '{name}' has unknown type '{kind}'")


def _mesh(mi, name: str, vertices: np.ndarray, faces: np.ndarray, bsdf) -> object:

    props = mi.Properties()
    props["bsdf"] = bsdf
    mesh = mi.Mesh(name, len(vertices), len(faces), props=props, has_vertex_normals=True)
    params = mi.traverse(mesh)
    # Flat buffers of the variant's own array types (scalar variants have no Point3f arrays).
    positions, indices = params["vertex_positions"], params["faces"]
    params["vertex_positions"] = type(positions)(np.ascontiguousarray(vertices, np.float32).ravel())
    params["faces"] = type(indices)(np.ascontiguousarray(faces, np.uint32).ravel())
    params.update()
    mesh.recompute_vertex_normals()
    return mesh


def shape_dict(mi, spec: dict, obj: dict):
    """Mitsuba shape (dict or instantiated mesh) of one spec object."""
    m = object_matrix(obj)
    bsdf = material_dict(mi, spec, obj["material"])
    shape = obj["shape"]
    if shape in ("rectangle", "box"):
        return {
            "type": "rectangle" if shape == "rectangle" else "cube",
            "to_world": mi.ScalarTransform4f(m.tolist()),
            "bsdf": bsdf,
        }
    if shape == "sphere":
        scale = np.asarray(obj.get("transform", {}).get("scale", (1, 1, 1)), dtype=np.float64)
        return {
            "type": "sphere",
            "center": m[:3, 3].tolist(),
            "radius": float(scale[0]),
            "bsdf": bsdf,
        }
    profile = [[1.0, 0.0], [1.0, 1.0]] if shape == "cylinder" else obj["profile"]
    try:
        vertices, faces = lathe_mesh(profile, int(obj.get("segments", 64)))
    except ValueError as err:
        raise SceneError(f"scene '{spec['name']}': object '{obj['name']}': {err}") from None
    world = vertices @ m[:3, :3].T + m[:3, 3]
    return _mesh(mi, obj["name"], world, faces, mi.load_dict(bsdf))


def light_dict(mi, light: dict) -> dict:
    """One-sided rectangular area light emitting towards its local +z."""
    return {
        "type": "rectangle",
        "to_world": mi.ScalarTransform4f(object_matrix(light).tolist()),
        "emitter": {"type": "area", "radiance": _rgb(light["radiance"])},
        "bsdf": {"type": "diffuse", "reflectance": _rgb((0.0, 0.0, 0.0))},
    }


def scene_dict(mi, spec: dict) -> dict:
    """Mitsuba scene dict (no sensor, no integrator) of a procedural spec.

    Shape keys are ``obj_<name>`` and ``light_<name>``, so ``shape.id()`` names the spec
    entry in ground-truth provenance.
    """
    out = {"type": "scene"}
    for obj in spec["objects"]:
        out[f"obj_{obj['name']}"] = shape_dict(mi, spec, obj)
    for light in spec["lights"]:
        out[f"light_{light['name']}"] = light_dict(mi, light)
    return out


def load_scene(mi, spec: dict):
    """Load a spec as a Mitsuba scene and return ``(scene, camera)``.

    Parameters
    ----------
    mi : module
        The ``mitsuba`` module with a variant set (see
        :func:`stereovar.renderers.mitsuba.backend.load_mitsuba`).
    spec : dict
        A validated scene spec (:func:`stereovar.scenes.spec.load_scene_spec`).

    Returns
    -------
    scene : mitsuba.Scene
    camera : Camera
        The left camera: from the spec, or from the XML file's first sensor.

    Raises
    ------
    SceneError
        If the XML file is missing, unparsable, or has no perspective sensor.
    """
    if "mitsuba_xml" in spec:
        return _load_xml(mi, spec["mitsuba_xml"])
    # Serial loading without shape merging: both parallel loading and the merging of shapes
    # that share a BSDF register shapes and emitters in a nondeterministic order, which
    # changes light selection, and so the render of a fixed seed, from one load to the next.
    scene = mi.load_dict(scene_dict(mi, spec), parallel=False, optimize=False)
    return scene, camera_from_spec(spec)


def _load_xml(mi, path: str):
    import os

    if not os.path.isfile(path):
        raise SceneError(f"Mitsuba scene file not found: {path}; fix 'mitsuba_xml' in the spec")
    try:
        scene = mi.load_file(path, parallel=False, optimize=False)  # see load_scene
    except Exception as err:  # mitsuba raises RuntimeError with a multi-line parser message
        first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise SceneError(f"cannot parse Mitsuba scene file {path}: {first}") from None
    sensors = scene.sensors()
    if not sensors:
        raise SceneError(f"Mitsuba scene file {path} has no sensor; add a perspective sensor")
    params = mi.traverse(sensors[0])
    keys = set(params.keys())
    if "x_fov" not in keys or "to_world" not in keys:
        raise SceneError(
            f"the first sensor of {path} is not a perspective camera; make it type='perspective'"
        )
    for key in ("principal_point_offset_x", "principal_point_offset_y"):
        if key in keys and abs(float(np.asarray(params[key]).ravel()[0])) > 1e-9:
            raise SceneError(
                f"the first sensor of {path} has a principal point offset; the rig needs a "
                "centred principal point, remove it"
            )
    to_world = np.asarray(params["to_world"].matrix, dtype=np.float64).reshape(4, 4)
    fov = float(np.asarray(params["x_fov"]).ravel()[0])
    return scene, Camera(to_world=to_world, fov_deg=fov)
