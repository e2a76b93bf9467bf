"""First hits of pixel-centre rays and material classes of shapes, with Mitsuba 3.

The renderer-specific half of the ground truth (paper Sec. 3.1): one ray through each pixel
centre is intersected with the compiled scene, and every shape's BSDF is mapped to a material
class. :mod:`stereovar.ground_truth` turns the hits into correspondence, occlusion and the
stored dataset.
"""

from __future__ import annotations

import numpy as np

from ...ground_truth import MATERIAL_CLASSES

_BSDF_CLASS_BY_NAME = {
    "SmoothDiffuse": "diffuse",
    "SmoothPlastic": "glossy",
    "RoughPlastic": "glossy",
    "Principled": "glossy",
    "PrincipledThin": "glossy",
    "SmoothConductor": "conductor",
    "RoughConductor": "conductor",
    "SmoothDielectric": "glass",
    "RoughDielectric": "glass",
    "ThinDielectric": "glass",
}


def classify_bsdf(mi, bsdf) -> str:
    """Material class of a Mitsuba BSDF, from its plugin type.

    Known plugin classes map directly (dielectric, roughdielectric and thindielectric are
    glass). Wrappers and unknown plugins fall back to their lobe flags: any transmission lobe
    makes glass; a diffuse lobe alone makes diffuse; diffuse plus glossy or delta reflection
    makes glossy; glossy or delta reflection alone makes conductor.
    """
    name = bsdf.class_name()
    if name in _BSDF_CLASS_BY_NAME:
        return _BSDF_CLASS_BY_NAME[name]
    flags = int(np.asarray(bsdf.flags()).ravel()[0])
    f = mi.BSDFFlags
    transmission = int(f.DeltaTransmission) | int(f.GlossyTransmission)
    transmission |= int(f.DiffuseTransmission)
    specular = int(f.DeltaReflection) | int(f.GlossyReflection)
    if flags & transmission:
        return "glass"
    if flags & int(f.DiffuseReflection):
        return "glossy" if flags & specular else "diffuse"
    if flags & specular:
        return "conductor"
    return "diffuse"


def shape_classes(mi, scene) -> tuple[np.ndarray, list[str]]:
    """Material class code and id of every shape of ``scene``, in ``scene.shapes()`` order.

    Emitting shapes are class ``emitter`` whatever their BSDF.
    """
    codes, names = [], []
    for shape in scene.shapes():
        cls = "emitter" if shape.is_emitter() else classify_bsdf(mi, shape.bsdf())
        codes.append(MATERIAL_CLASSES.index(cls))
        names.append(shape.id())
    return np.asarray(codes, dtype=np.uint8), names


def trace_pixel_centres(mi, scene, sensor, width: int, height: int):
    """Intersect one ray through each pixel centre with the scene.

    Parameters
    ----------
    mi : module
        ``mitsuba`` with a variant set.
    scene : mitsuba.Scene
    sensor : mitsuba.Sensor
    width, height : int

    Returns
    -------
    hit : numpy.ndarray, shape (height, width), bool
    points : numpy.ndarray, shape (height, width, 3), float64
        First-hit points (undefined where not ``hit``).
    normals : numpy.ndarray, shape (height, width, 3), float64
        Geometric normals at the hits.
    shape_index : numpy.ndarray, shape (height, width), int32
        Index into ``scene.shapes()``; -1 where not ``hit``.
    """
    if mi.variant().startswith("scalar"):
        return _trace_scalar(mi, scene, sensor, width, height)
    import drjit as dr

    idx = dr.arange(mi.UInt32, width * height)
    x = mi.Float(idx % width) + 0.5
    y = mi.Float(idx // width) + 0.5
    ray, _ = sensor.sample_ray(
        0.0, 0.5, mi.Point2f(x / width, y / height), mi.Point2f(0.5, 0.5), True
    )
    si = scene.ray_intersect(ray)
    hit = np.asarray(si.is_valid(), dtype=bool)
    points = np.stack([np.asarray(c, dtype=np.float64) for c in si.p], axis=-1)
    normals = np.stack([np.asarray(c, dtype=np.float64) for c in si.n], axis=-1)
    ids = np.asarray(dr.reinterpret_array(mi.UInt32, si.shape), dtype=np.int64)
    registry = np.asarray(
        [
            int(np.asarray(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(s)))[0])
            for s in scene.shapes()
        ],
        dtype=np.int64,
    )
    order = np.argsort(registry)
    pos = np.clip(np.searchsorted(registry[order], ids), 0, len(registry) - 1)
    found = hit & (registry[order][pos] == ids)
    shape_index = np.where(found, order[pos], -1).astype(np.int32)
    shape = (height, width)
    return (
        found.reshape(shape),
        points.reshape(*shape, 3),
        normals.reshape(*shape, 3),
        shape_index.reshape(shape),
    )


def _trace_scalar(mi, scene, sensor, width, height):
    shapes = list(scene.shapes())
    hit = np.zeros((height, width), dtype=bool)
    points = np.zeros((height, width, 3))
    normals = np.zeros((height, width, 3))
    shape_index = np.full((height, width), -1, dtype=np.int32)
    for j in range(height):
        for i in range(width):
            pos = mi.Point2f((i + 0.5) / width, (j + 0.5) / height)
            ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5), True)
            si = scene.ray_intersect(ray)
            if not si.is_valid():
                continue
            hit[j, i] = True
            points[j, i] = [si.p[0], si.p[1], si.p[2]]
            normals[j, i] = [si.n[0], si.n[1], si.n[2]]
            shape_index[j, i] = next(k for k, s in enumerate(shapes) if s == si.shape)
    return hit, points, normals, shape_index
