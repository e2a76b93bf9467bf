"""The generator's checks of a layout (:mod:`stereovar.scenes.generate`): a small numpy ray
caster in the left camera (:func:`raycast_labels`) that measures what each pixel sees
(:func:`glass_coverage`, :func:`estimate_glass_fraction`), and the simple lighting model
(:func:`predicted_mean_radiance`) the light radiances are scaled by.

It intersects boxes, spheres and cylinders exactly and lathe vases by an inscribed stack of
cylinders, so it errs low for glass; the renderer-side ground truth is the final judge.
"""

from __future__ import annotations

import numpy as np

from ..geometry import camera_frame, focal_length_px, object_matrix, project_points
from .builder import rounded

ESTIMATE_SIZE = (320, 180)
"""Image size (width, height) of the generator's ray-cast checks; same aspect as 1280x720."""

EXPOSURE_TARGET = 0.28
"""Mean left-view pixel value (linear RGB) the light radiances are scaled to."""

#: Ratio of the mean of a Mitsuba render (path, max_depth 8) to the simple lighting model of
#: :func:`predicted_mean_radiance`; calibrated on the 20 committed scenes.
EXPOSURE_CALIBRATION = 1.05

EXPOSURE_SIZE = (96, 54)
"""Image size of the lighting model's ray cast."""


# --------------------------------------------------------------------------------------------
# ray casting (numpy) for the generator's checks
# --------------------------------------------------------------------------------------------


def camera_rays(camera: dict, width: int, height: int):
    """World-space rays through the pixel centres of a spec camera.

    Returns
    -------
    origin : numpy.ndarray, shape (3,)
    directions : numpy.ndarray, shape (height, width, 3)
        Unnormalised; the component along the optical axis is 1.
    """
    origin = np.asarray(camera["origin"], dtype=np.float64)
    frame = camera_frame(origin, camera["target"], camera.get("up", (0.0, 1.0, 0.0)))
    f = focal_length_px(camera.get("fov_deg", 60.0), width)
    u = np.arange(width) + 0.5
    v = np.arange(height) + 0.5
    xc = (0.5 * width - u)[None, :] / f
    yc = (0.5 * height - v)[:, None] / f
    cam = np.stack(np.broadcast_arrays(xc, yc, np.ones((1, 1))), axis=-1)
    return origin, cam @ frame


def _local(o, d, m):
    inv = np.linalg.inv(m)
    return inv[:3, :3] @ o + inv[:3, 3], d @ inv[:3, :3].T


def _hit_rect(o, d):
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -o[2] / d[..., 2]
    p = o + t[..., None] * d
    ok = (t > 1e-6) & (np.abs(p[..., 0]) <= 1) & (np.abs(p[..., 1]) <= 1)
    return np.where(ok, t, np.inf)


def _hit_box(o, d):
    """Slab test against the canonical box [-1, 1]^3 (fmin/fmax skip 0 * inf NaNs)."""
    tn = np.full(d.shape[:-1], -np.inf)
    tf = np.full(d.shape[:-1], np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        for a in range(3):
            inv = 1.0 / d[..., a]
            t1 = (-1.0 - o[a]) * inv
            t2 = (1.0 - o[a]) * inv
            tn = np.fmax(tn, np.fmin(t1, t2))
            tf = np.fmin(tf, np.fmax(t1, t2))
    t = np.where(tn > 1e-6, tn, tf)
    return np.where((tf >= tn) & (t > 1e-6), t, np.inf)


def _hit_sphere(o, d):
    a = np.einsum("...i,...i", d, d)
    b = 2.0 * (d @ o)
    c = o @ o - 1.0
    disc = b * b - 4 * a * c
    sq = np.sqrt(np.maximum(disc, 0.0))
    t0 = (-b - sq) / (2 * a)
    t1 = (-b + sq) / (2 * a)
    t = np.where(t0 > 1e-6, t0, t1)
    return np.where((disc >= 0) & (t > 1e-6), t, np.inf)


def _hit_cylinder(o, d, r=1.0, y0=0.0, y1=1.0):
    """Closed cylinder of radius ``r`` about +y between ``y0`` and ``y1``."""
    a = d[..., 0] ** 2 + d[..., 2] ** 2
    b = 2 * (o[0] * d[..., 0] + o[2] * d[..., 2])
    c = o[0] ** 2 + o[2] ** 2 - r * r
    disc = b * b - 4 * a * c
    sq = np.sqrt(np.maximum(disc, 0.0))
    best = np.full(d.shape[:-1], np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        for t in ((-b - sq) / (2 * a), (-b + sq) / (2 * a)):
            y = o[1] + t * d[..., 1]
            ok = (disc >= 0) & (a > 0) & (t > 1e-6) & (y >= y0) & (y <= y1)
            best = np.where(ok & (t < best), t, best)
        for yc in (y0, y1):
            t = (yc - o[1]) / d[..., 1]
            x = o[0] + t * d[..., 0]
            z = o[2] + t * d[..., 2]
            ok = (t > 1e-6) & (x * x + z * z <= r * r)
            best = np.where(ok & (t < best), t, best)
    return best


def _hit_lathe(o, d, profile, sub: int = 4):
    """Inscribed stack of cylinders of a lathe profile (never larger than the solid)."""
    prof = np.asarray(profile, dtype=np.float64)
    best = np.full(d.shape[:-1], np.inf)
    for (ra, ya), (rb, yb) in zip(prof[:-1], prof[1:], strict=False):
        for k in range(sub):
            r0 = ra + (rb - ra) * k / sub
            r1 = ra + (rb - ra) * (k + 1) / sub
            y0 = ya + (yb - ya) * k / sub
            y1 = ya + (yb - ya) * (k + 1) / sub
            r = min(r0, r1)
            if r <= 0 or y1 <= y0:
                continue
            best = np.minimum(best, _hit_cylinder(o, d, r, y0, y1))
    return best


def _local_bounds(obj: dict) -> np.ndarray:
    """Corners (8, 3) of a canonical shape's object-space bounding box."""
    shape = obj["shape"]
    if shape == "rectangle":
        lo, hi = (-1.0, -1.0, 0.0), (1.0, 1.0, 0.0)
    elif shape in ("box", "sphere"):
        lo, hi = (-1.0, -1.0, -1.0), (1.0, 1.0, 1.0)
    elif shape == "cylinder":
        lo, hi = (-1.0, 0.0, -1.0), (1.0, 1.0, 1.0)
    else:
        prof = np.asarray(obj["profile"], dtype=np.float64)
        r = float(prof[:, 0].max())
        lo, hi = (-r, float(prof[:, 1].min()), -r), (r, float(prof[:, 1].max()), r)
    return np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )


def _pixel_window(obj, m, origin, frame, f, width, height):
    """Pixel rows/columns slices that can see ``obj`` (whole image if it straddles the eye)."""
    corners = _local_bounds(obj) @ m[:3, :3].T + m[:3, 3]
    u, v, z = project_points(
        corners, origin=origin, frame=frame, focal_px=f, width=width, height=height
    )
    if np.any(z <= 1e-3):
        return slice(0, height), slice(0, width)
    c0 = int(max(0, np.floor(np.min(u)) - 1))
    c1 = int(min(width, np.ceil(np.max(u)) + 1))
    r0 = int(max(0, np.floor(np.min(v)) - 1))
    r1 = int(min(height, np.ceil(np.max(v)) + 1))
    return slice(r0, max(r0, r1)), slice(c0, max(c0, c1))


def _raycast(spec: dict, width: int, height: int):
    """First hits: ``(labels, t, origin, dirs, entries)``; see :func:`raycast_labels`."""
    cam = spec["camera"]
    origin, dirs = camera_rays(cam, width, height)
    frame = camera_frame(origin, cam["target"], cam.get("up", (0.0, 1.0, 0.0)))
    f = focal_length_px(cam.get("fov_deg", 60.0), width)
    entries = list(spec.get("objects", [])) + [
        {**light, "shape": "rectangle"} for light in spec.get("lights", [])
    ]
    best = np.full((height, width), np.inf)
    labels = np.full((height, width), -1, dtype=np.int64)
    for k, obj in enumerate(entries):
        m = object_matrix(obj)
        rows, cols = _pixel_window(obj, m, origin, frame, f, width, height)
        if rows.start >= rows.stop or cols.start >= cols.stop:
            continue
        o, d = _local(origin, dirs[rows, cols], m)
        shape = obj["shape"]
        if shape == "rectangle":
            t = _hit_rect(o, d)
        elif shape == "box":
            t = _hit_box(o, d)
        elif shape == "sphere":
            t = _hit_sphere(o, d)
        elif shape == "cylinder":
            t = _hit_cylinder(o, d)
        elif shape == "lathe":
            t = _hit_lathe(o, d, obj["profile"])
        else:
            raise ValueError(f"unknown shape {shape!r}")
        window = best[rows, cols]
        closer = t < window
        best[rows, cols] = np.where(closer, t, window)
        labels[rows, cols] = np.where(closer, k, labels[rows, cols])
    return labels, best, origin, dirs, entries


def raycast_labels(spec: dict, *, width: int, height: int) -> tuple[np.ndarray, list[dict]]:
    """First-hit labels of one ray per pixel centre of the spec's (left) camera.

    Parameters
    ----------
    spec : dict
        A procedural scene spec.
    width, height : int
        Image size in pixels.

    Returns
    -------
    labels : numpy.ndarray, shape (height, width), int
        Index into ``entries`` of the first surface hit, ``-1`` where the ray escapes.
    entries : list of dict
        The spec's objects followed by its lights.

    Notes
    -----
    Rectangles, boxes, spheres and cylinders are intersected exactly; lathes by an inscribed
    stack of cylinders (4 per profile segment), which under-estimates their silhouette.
    """
    labels, _, _, _, entries = _raycast(spec, width, height)
    return labels, entries


def _local_normals(obj: dict, local_points: np.ndarray) -> np.ndarray:
    """Outward normals (object space) of a canonical shape at points on its surface."""
    p = local_points
    shape = obj["shape"]
    if shape == "rectangle":
        return np.broadcast_to(np.array([0.0, 0.0, 1.0]), p.shape).copy()
    if shape == "box":
        axis = np.argmax(np.abs(p), axis=-1)
        n = np.zeros_like(p)
        n[np.arange(len(p)), axis] = np.sign(p[np.arange(len(p)), axis])
        return n
    if shape == "sphere":
        return p
    if shape == "cylinder":
        y0, y1 = 0.0, 1.0
    else:
        y0, y1 = obj["profile"][0][1], obj["profile"][-1][1]
    n = np.stack([p[:, 0], np.zeros(len(p)), p[:, 2]], axis=-1)
    n[p[:, 1] <= y0 + 1e-4] = (0.0, -1.0, 0.0)
    n[p[:, 1] >= y1 - 1e-4] = (0.0, 1.0, 0.0)
    return n


def _albedo(spec: dict, material: str) -> float | None:
    """Mean diffuse albedo of a material, or ``None`` for specular ones (metal, glass)."""
    mat = spec["materials"][material]
    if mat["type"] not in ("diffuse", "glossy"):
        return None
    if "texture" in mat:
        rgb = np.mean(spec["textures"][mat["texture"]]["colors"], axis=0)
    else:
        rgb = np.asarray(mat["reflectance"], dtype=np.float64)
    return float(np.mean(rgb)) * 0.85  # patterns darken their base colours (gaps, grout)


def predicted_mean_radiance(
    spec: dict, *, width: int = EXPOSURE_SIZE[0], height: int = EXPOSURE_SIZE[1]
) -> float:
    r"""Mean left-view pixel value predicted by a simple one-bounce-plus-ambient model.

    .. math::

        \hat I(p) = \frac{\rho(p)}{\pi}\Bigl(
            \sum_{\ell} L_\ell \int_{A_\ell}
                \frac{\cos\theta_\ell \cos\theta_p}{r^2}\,dA
            + \frac{\bar\rho}{1-\bar\rho}\,\frac{\pi \sum_\ell L_\ell A_\ell}{S}\Bigr)

    for the first hit ``p`` of each pixel's ray: direct light from a 4x4 grid of points on each
    panel (shadows ignored) plus a uniform inter-reflected irradiance from the emitted power
    spread over the room's surface area ``S`` with mean room albedo :math:`\bar\rho`.
    Specular hits (metal, glass) take the mean of the diffuse ones. Multiply by
    :data:`EXPOSURE_CALIBRATION` to compare with a path-traced render.
    """
    labels, t, origin, dirs, entries = _raycast(spec, width, height)
    n_obj = len(spec["objects"])
    lab = labels.ravel()
    tt = t.ravel()
    dd = dirs.reshape(-1, 3)
    pts = origin + tt[:, None] * dd
    normals = np.zeros_like(pts)
    albedo = np.full(len(lab), np.nan)
    for k in np.unique(lab):
        if k < 0 or k >= n_obj:
            continue
        obj = entries[k]
        sel = lab == k
        m = object_matrix(obj)
        inv = np.linalg.inv(m)
        lp = pts[sel] @ inv[:3, :3].T + inv[:3, 3]
        n = _local_normals(obj, lp) @ inv[:3, :3]
        n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-12)
        flip = np.einsum("ij,ij->i", n, dd[sel]) > 0
        n[flip] *= -1
        normals[sel] = n
        a = _albedo(spec, obj["material"])
        if a is not None:
            albedo[sel] = a
    # direct irradiance from sampled light points
    e_direct = np.zeros(len(lab))
    power = 0.0
    g = (np.arange(4) + 0.5) / 4 * 2 - 1
    gx, gy = np.meshgrid(g, g)
    local = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size), np.ones(gx.size)], axis=-1)
    for light in spec["lights"]:
        m = object_matrix(light)
        lpts = (local @ m.T)[:, :3]
        ln = m[:3, :3] @ np.array([0.0, 0.0, 1.0])
        area = float(np.linalg.norm(np.cross(m[:3, 0], m[:3, 1]))) * 4.0
        ln /= np.linalg.norm(ln)
        radiance = float(np.mean(light["radiance"]))
        power += np.pi * radiance * area
        dA = area / len(lpts)
        for q in lpts:
            v = q - pts
            r2 = np.maximum(np.einsum("ij,ij->i", v, v), 1e-4)
            v /= np.sqrt(r2)[:, None]
            cos_p = np.clip(np.einsum("ij,ij->i", normals, v), 0.0, None)
            cos_l = np.clip(-(v @ ln), 0.0, None)
            e_direct += radiance * dA * cos_p * cos_l / r2
    # ambient inter-reflection over the room's surfaces
    room = [o for o in spec["objects"] if o["name"].startswith(("floor", "ceiling", "wall_"))]
    areas = np.array(
        [4 * abs(o["transform"]["scale"][0] * o["transform"]["scale"][1]) for o in room]
    )
    rhos = np.array([_albedo(spec, o["material"]) or 0.5 for o in room])
    rho = float(np.sum(areas * rhos) / np.sum(areas))
    e_ambient = rho / (1.0 - rho) * power / float(np.sum(areas))
    value = albedo / np.pi * (e_direct + e_ambient)
    diffuse = np.isfinite(value)
    if not diffuse.any():
        return 0.0
    value[~diffuse] = np.mean(value[diffuse])
    return float(np.mean(value))


def normalise_exposure(spec: dict) -> float:
    """Scale all light radiances so the predicted left-view mean is the target; return it."""
    predicted = predicted_mean_radiance(spec) * EXPOSURE_CALIBRATION
    scale = EXPOSURE_TARGET / predicted if predicted > 0 else 1.0
    for light in spec["lights"]:
        light["radiance"] = rounded([c * scale for c in light["radiance"]], 3)
    return predicted * scale


def glass_coverage(spec: dict, *, width: int = ESTIMATE_SIZE[0], height: int = ESTIMATE_SIZE[1]):
    """Visible-glass statistics of a spec's left view from :func:`raycast_labels`.

    Returns
    -------
    dict
        ``fraction`` (share of pixels whose first hit is glass), ``per_object`` (share per
        glass object name), ``by_type`` (share per material type: diffuse, glossy, conductor,
        glass), ``light_fraction`` (share of pixels that see a light directly) and
        ``miss_fraction`` (share of rays that hit nothing).
    """
    labels, entries = raycast_labels(spec, width=width, height=height)
    materials = spec.get("materials", {})
    n_obj = len(spec.get("objects", []))
    total = labels.size
    counts = np.bincount(labels[labels >= 0].ravel(), minlength=len(entries))
    per_object = {}
    by_type = dict.fromkeys(("diffuse", "glossy", "conductor", "glass"), 0.0)
    for k, obj in enumerate(entries[:n_obj]):
        kind = materials.get(obj["material"], {}).get("type")
        share = float(counts[k]) / total
        if kind in by_type:
            by_type[kind] += share
        if kind == "glass":
            per_object[obj["name"]] = share
    return {
        "fraction": by_type["glass"],
        "per_object": per_object,
        "by_type": by_type,
        "light_fraction": float(counts[n_obj:].sum()) / total,
        "miss_fraction": float((labels < 0).sum()) / total,
    }


def estimate_glass_fraction(
    spec: dict, *, width: int = ESTIMATE_SIZE[0], height: int = ESTIMATE_SIZE[1]
) -> float:
    """Share of the left view's pixels whose first hit is glass (ray-cast estimate).

    The default 320x180 grid has the aspect of the paper's 1280x720 views; the fraction is
    resolution-independent up to sampling error.
    """
    return glass_coverage(spec, width=width, height=height)["fraction"]
