"""Compile renderer-neutral scene specs into a Blender scene rendered by Cycles.

The same spec gives the same geometry as :mod:`stereovar.renderers.mitsuba.scene`:

* rectangles are Mitsuba's ``[-1, 1]^2`` quad with its texture coordinates
  :math:`(u, v) = ((x + 1)/2, (y + 1)/2)`; boxes are Mitsuba's own ``cube`` mesh (positions,
  texture coordinates and flat faces read from Mitsuba); cylinders and lathes are
  :func:`~stereovar.renderers.mitsuba.scene.lathe_mesh` with smooth normals and, as in
  Mitsuba for a mesh without texture coordinates, the barycentric :math:`(u, v) = (b_1, b_2)`;
  spheres, analytic in Mitsuba, are UV spheres of :data:`SPHERE_SEGMENTS` segments with
  Mitsuba's :math:`(u, v) = (\\phi / 2\\pi, \\theta / \\pi)` (largest radial error
  :math:`r (1 - \\cos(\\pi / n))`, 7.5e-5 r);
* every mesh is placed in world space by the spec's transform, so the objects' own matrices
  are the identity;
* textures are the same baked bitmaps (:func:`~stereovar.renderers.mitsuba.scene.baked_texture`),
  read raw (non-colour) with bilinear filtering and repeat, scaled by the spec's ``repeat``;
* materials: ``diffuse`` → Diffuse BSDF; ``glossy`` → Principled BSDF (dielectric, base colour
  the reflectance, IOR the spec's); ``conductor`` → Principled BSDF, metallic, base colour the
  normal-incidence reflectance of Mitsuba's measured conductor (:func:`conductor_rgb`);
  ``glass`` → Glass BSDF with the spec's IOR relative to Mitsuba's air (1.000277) and its
  tint. Roughness maps as :math:`r = \\sqrt{\\alpha}` (Blender squares its roughness into the
  microfacet :math:`\\alpha`);
* lights are one-sided emissive rectangles: an Emission shader of strength 1 and colour the
  spec's radiance on the front (+z), black diffuse behind, sampled from the front only.
  Cycles' emission strength 1 is a radiance of 1 W m^-2 sr^-1 per unit colour, the unit of
  Mitsuba's ``radiance``, so the conversion factor is 1.

Known gaps against Mitsuba: Mitsuba's rough materials use the Beckmann distribution and
Principled BSDF only GGX (the Glass BSDF uses Beckmann); Mitsuba's ``plastic`` is a diffuse
base under a dielectric coating with internal scattering, Principled's dielectric is a
layered approximation; Mitsuba's conductors use spectral complex IOR data at every angle,
Principled's metallic lobe the F82-tint model from the normal-incidence colour; the glass
tint applies to transmission only in Mitsuba and to both lobes in Blender.
"""

from __future__ import annotations

import json
import math
from functools import lru_cache

import numpy as np

from ...errors import SceneError
from ...geometry import object_matrix
from ..mitsuba.scene import baked_texture, lathe_mesh

SPHERE_SEGMENTS = 256
"""Azimuthal segments of a sphere's mesh (half as many rings)."""

MITSUBA_AIR_IOR = 1.000277
"""Mitsuba's ``ext_ior`` of glass (:func:`stereovar.renderers.mitsuba.scene.material_dict`);
Blender's exterior is vacuum, so the Glass BSDF gets ``int_ior / ext_ior``."""


# --------------------------------------------------------------------------------------------
# geometry
# --------------------------------------------------------------------------------------------


def rectangle_mesh() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mitsuba's ``rectangle``: vertices, faces and per-vertex texture coordinates."""
    v = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])
    f = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)
    return v, f, (v[:, :2] + 1.0) / 2.0


@lru_cache(maxsize=1)
def cube_mesh() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mitsuba's own ``cube`` mesh (24 vertices, 12 faces, texture coordinates)."""
    from ..mitsuba.backend import load_mitsuba

    mi = load_mitsuba("auto")
    params = mi.traverse(mi.load_dict({"type": "cube"}))
    v = np.asarray(params["vertex_positions"], dtype=np.float64).reshape(-1, 3)
    f = np.asarray(params["faces"], dtype=np.uint32).reshape(-1, 3)
    uv = np.asarray(params["vertex_texcoords"], dtype=np.float64).reshape(-1, 2)
    return v, f, uv


def sphere_mesh(segments: int = SPHERE_SEGMENTS):
    r"""Unit UV sphere with Mitsuba's sphere parameterisation.

    .. math::

        p = (\sin\theta\cos\phi, \sin\theta\sin\phi, \cos\theta), \quad
        (u, v) = (\phi / 2\pi, \theta / \pi)

    Returns vertices, faces (counter-clockwise from outside) and per-vertex texture
    coordinates; the seam and the poles have their own vertices so coordinates do not wrap.
    """
    rings = segments // 2
    theta = np.linspace(0.0, np.pi, rings + 1)
    phi = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    v = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1).reshape(-1, 3)
    uv = np.stack([p / (2 * np.pi), t / np.pi], -1).reshape(-1, 2)
    idx = np.arange((rings + 1) * (segments + 1)).reshape(rings + 1, segments + 1)
    a, b = idx[:-1, :-1], idx[:-1, 1:]
    c, d = idx[1:, :-1], idx[1:, 1:]
    faces = np.concatenate(
        [np.stack([a, d, b], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)]
    )
    tri = v[faces]
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    return v, faces[area > 1e-14].astype(np.uint32), uv


def shape_geometry(spec: dict, obj: dict) -> dict:
    """World-space mesh of one spec object: ``vertices``, ``faces``, per-corner texture
    coordinates ``loop_uv`` (F, 3, 2) and ``smooth`` shading."""
    m = object_matrix(obj)
    shape = obj["shape"]
    if shape in ("rectangle", "box"):
        v, f, uv = rectangle_mesh() if shape == "rectangle" else cube_mesh()
        world = v @ m[:3, :3].T + m[:3, 3]
        return {"vertices": world, "faces": f, "loop_uv": uv[f], "smooth": False}
    if shape == "sphere":
        scale = np.asarray(obj.get("transform", {}).get("scale", (1, 1, 1)), dtype=np.float64)
        v, f, uv = sphere_mesh()
        world = v * float(scale[0]) + m[:3, 3]  # Mitsuba's sphere: centre and radius only
        return {"vertices": world, "faces": f, "loop_uv": uv[f], "smooth": True}
    profile = [[1.0, 0.0], [1.0, 1.0]] if shape == "cylinder" else obj["profile"]
    try:
        v, f = lathe_mesh(profile, int(obj.get("segments", 64)))
    except ValueError as err:
        raise SceneError(f"scene '{spec['name']}': object '{obj['name']}': {err}") from None
    world = v @ m[:3, :3].T + m[:3, 3]
    barycentric = np.broadcast_to(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), (len(f), 3, 2))
    return {"vertices": world, "faces": f, "loop_uv": barycentric, "smooth": True}


def _mesh_object(bpy, name: str, geometry: dict, material):
    mesh = bpy.data.meshes.new(name)
    vertices = np.ascontiguousarray(geometry["vertices"], dtype=np.float32)
    faces = np.ascontiguousarray(geometry["faces"], dtype=np.int32)
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", vertices.ravel())
    mesh.loops.add(faces.size)
    mesh.loops.foreach_set("vertex_index", faces.ravel())
    mesh.polygons.add(len(faces))
    mesh.polygons.foreach_set("loop_start", np.arange(0, faces.size, 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(len(faces), 3, dtype=np.int32))
    mesh.polygons.foreach_set("use_smooth", np.full(len(faces), geometry["smooth"], dtype=bool))
    uv = mesh.uv_layers.new(name="UVMap")
    uv.data.foreach_set("uv", np.ascontiguousarray(geometry["loop_uv"], np.float32).ravel())
    mesh.update(calc_edges=True)
    mesh.validate(clean_customdata=False)
    mesh.materials.append(material)
    ob = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    return ob


# --------------------------------------------------------------------------------------------
# materials
# --------------------------------------------------------------------------------------------


@lru_cache(maxsize=16)
def conductor_rgb(metal: str) -> tuple[float, float, float]:
    """Normal-incidence RGB reflectance of Mitsuba's measured conductor ``metal`` (its
    smooth ``conductor`` BSDF sampled at normal incidence): the base colour of the
    Principled metallic lobe."""
    from ..mitsuba.backend import load_mitsuba

    mi = load_mitsuba("auto")
    bsdf = mi.load_dict({"type": "conductor", "material": metal})
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
    _, weight = bsdf.sample(mi.BSDFContext(), si, 0.5, mi.Point2f(0.5, 0.5))
    rgb = np.asarray(weight, dtype=np.float64).reshape(-1)[:3]
    return tuple(float(c) for c in rgb)


def _texture_node(bpy, nodes, links, spec: dict, name: str):
    tex = spec["textures"][name]
    key = f"tex_{name}"
    image = bpy.data.images.get(key)
    if image is None:
        baked = np.asarray(baked_texture(json.dumps(tex, sort_keys=True)), np.float32)
        height, width = baked.shape[:2]
        rgba = np.ones((height, width, 4), dtype=np.float32)
        rgba[..., :3] = baked[..., :3] if baked.ndim == 3 else baked[..., None]
        image = bpy.data.images.new(key, width, height, alpha=False, float_buffer=True)
        image.colorspace_settings.name = "Non-Color"
        # Blender stores rows from v = 0 upwards, as Mitsuba's bitmap indexes them.
        image.pixels.foreach_set(rgba.ravel())
        image.pack()
    node = nodes.new("ShaderNodeTexImage")
    node.image = image
    node.interpolation = "Linear"
    node.extension = "REPEAT"
    coords = nodes.new("ShaderNodeTexCoord")
    mapping = nodes.new("ShaderNodeMapping")
    su, sv = tex.get("repeat", (1.0, 1.0))
    mapping.inputs["Scale"].default_value = (float(su), float(sv), 1.0)
    links.new(coords.outputs["UV"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], node.inputs["Vector"])
    return node.outputs["Color"]


def _colour(bpy, nodes, links, spec, mat, socket, key="reflectance"):
    if "texture" in mat:
        links.new(_texture_node(bpy, nodes, links, spec, mat["texture"]), socket)
    else:
        socket.default_value = (*[float(c) for c in mat[key]], 1.0)


def material(bpy, spec: dict, name: str):
    """The Blender material of spec material ``name`` (see the module notes)."""
    mat = spec["materials"][name]
    kind = mat["type"]
    rough = math.sqrt(max(float(mat.get("roughness", 0.0)), 0.0))
    out = bpy.data.materials.new(f"mat_{name}")
    nodes, links = out.node_tree.nodes, out.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    if kind == "diffuse":
        bsdf = nodes.new("ShaderNodeBsdfDiffuse")
        bsdf.inputs["Roughness"].default_value = 0.0  # Lambertian
        _colour(bpy, nodes, links, spec, mat, bsdf.inputs["Color"])
    elif kind in ("glossy", "conductor"):
        bsdf = nodes.new("ShaderNodeBsdfPrincipled")
        bsdf.inputs["Roughness"].default_value = rough
        if kind == "glossy":
            bsdf.inputs["Metallic"].default_value = 0.0
            bsdf.inputs["IOR"].default_value = float(mat.get("ior", 1.49))
            _colour(bpy, nodes, links, spec, mat, bsdf.inputs["Base Color"])
        else:
            bsdf.inputs["Metallic"].default_value = 1.0
            bsdf.inputs["Base Color"].default_value = (*conductor_rgb(mat["metal"]), 1.0)
    elif kind == "glass":
        bsdf = nodes.new("ShaderNodeBsdfGlass")
        bsdf.distribution = "BECKMANN"
        bsdf.inputs["Roughness"].default_value = rough
        bsdf.inputs["IOR"].default_value = float(mat.get("ior", 1.5)) / MITSUBA_AIR_IOR
        tint = [float(c) for c in mat.get("tint", (1.0, 1.0, 1.0))]
        bsdf.inputs["Color"].default_value = (*tint, 1.0)
    else:
        raise SceneError(f"scene '{spec['name']}': material '{name}' has unknown type '{kind}'")
    links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    return out


def light_material(bpy, name: str, radiance):
    """One-sided emitter: radiance ``radiance`` (W m^-2 sr^-1) from the front face, black
    diffuse behind (Mitsuba's ``area`` emitter on a rectangle with a black BSDF)."""
    out = bpy.data.materials.new(f"light_{name}")
    nodes, links = out.node_tree.nodes, out.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (*[float(c) for c in radiance], 1.0)
    emission.inputs["Strength"].default_value = 1.0
    black = nodes.new("ShaderNodeBsdfDiffuse")
    black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    geometry = nodes.new("ShaderNodeNewGeometry")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    links.new(emission.outputs["Emission"], mix.inputs[1])
    links.new(black.outputs["BSDF"], mix.inputs[2])
    links.new(mix.outputs["Shader"], output.inputs["Surface"])
    out.cycles.emission_sampling = "FRONT"
    return out


# --------------------------------------------------------------------------------------------
# scene and camera
# --------------------------------------------------------------------------------------------


def camera_matrix(to_world) -> np.ndarray:
    """Blender camera matrix of a Mitsuba camera-to-world matrix.

    Mitsuba's camera axes are x image-left, y up, z forward; Blender's are x image-right,
    y up, z backward, so x and z change sign (a rotation by pi about y).
    """
    m = np.asarray(to_world, dtype=np.float64).reshape(4, 4).copy()
    m[:3, 0] *= -1.0
    m[:3, 2] *= -1.0
    return m


def build_scene(bpy, spec: dict, *, width: int, height: int, fov_deg: float, shape_ids):
    """Replace Blender's data with the compiled spec; returns the camera object.

    ``shape_ids`` lists the Mitsuba shape ids (``obj_<name>``, ``light_<name>``) in the order
    of :attr:`~stereovar.renderers.base.FirstHits.shape_index`; each object's pass index is
    its position there plus one (0 is the background of the IndexOB pass).
    """
    if "objects" not in spec:
        raise SceneError(
            f"scene '{spec['name']}' is a Mitsuba XML scene; the Cycles renderer compiles "
            "procedural specs only: render it with render.renderer: mitsuba"
        )
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    index = {sid: k + 1 for k, sid in enumerate(shape_ids)}
    for obj in spec["objects"]:
        ob = _mesh_object(
            bpy,
            f"obj_{obj['name']}",
            shape_geometry(spec, obj),
            material(bpy, spec, obj["material"]),
        )
        ob.pass_index = index.get(f"obj_{obj['name']}", 0)
    for light in spec["lights"]:
        v, f, uv = rectangle_mesh()
        m = object_matrix(light)
        geometry = {
            "vertices": v @ m[:3, :3].T + m[:3, 3],
            "faces": f,
            "loop_uv": uv[f],
            "smooth": False,
        }
        ob = _mesh_object(
            bpy,
            f"light_{light['name']}",
            geometry,
            light_material(bpy, light["name"], light["radiance"]),
        )
        ob.pass_index = index.get(f"light_{light['name']}", 0)
    world = bpy.data.worlds.new("black")
    background = world.node_tree.nodes.get("Background")
    if background is not None:
        background.inputs["Strength"].default_value = 0.0
    scene.world = world
    cam = bpy.data.cameras.new("camera")
    cam.type = "PERSP"
    cam.sensor_fit = "HORIZONTAL"
    cam.angle = math.radians(fov_deg)
    cam.clip_start = 1e-3
    cam.clip_end = 1e4
    cam.shift_x = cam.shift_y = 0.0
    camera = bpy.data.objects.new("camera", cam)
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.render.resolution_x = int(width)
    scene.render.resolution_y = int(height)
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
    scene.render.use_border = False
    return camera

