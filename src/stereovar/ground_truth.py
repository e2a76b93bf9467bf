"""Ground truth for a stereo pair: planar depth, subpixel disparity, material classes, masks.

One ray goes through each pixel centre of each view (paper Sec. 3.1). The first hit point is
projected into the other camera; the horizontal offset of the projection is the disparity.
Pixels that miss the scene, or whose correspondence falls outside the other image, are
invalid; invalid pixels hold 0 in the float fields, so NaN or Inf never reach a stored field.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .io.renders import pixel_coords
from .rig import VIEWS, StereoRig

MATERIAL_CLASSES = ("background", "diffuse", "glossy", "conductor", "glass", "emitter")
"""Material class names; the stored ``material`` code is the index into this tuple."""


def refine_hits(origin, directions, points, normals) -> np.ndarray:
    r"""Re-intersect each ray with the tangent plane at its float32 hit, in float64.

    .. math:: P' = O + \frac{n \cdot (P - O)}{n \cdot \omega}\,\omega

    Mitsuba reports hit points in float32, whose error along the ray is far larger than
    across it on large primitives; intersecting the float64 pixel ray with the tangent plane
    keeps the subpixel disparity accurate to ~1e-6 px. Falls back to ``P`` where the ray
    grazes the plane.
    """
    o = np.asarray(origin, dtype=np.float64)
    denom = np.einsum("...i,...i->...", normals, directions)
    num = np.einsum("...i,...i->...", normals, points - o)
    ok = np.abs(denom) > 1e-6 * np.linalg.norm(directions, axis=-1)
    t = np.where(ok, num / np.where(ok, denom, 1.0), np.nan)
    refined = o + t[..., None] * directions
    return np.where((ok & np.isfinite(t))[..., None], refined, points)


def correspondence(points, hit, rig: StereoRig, view: str) -> dict:
    """Disparity, depth and validity of one view's first-hit points (Eq. 2 geometry).

    For a pixel of ``view`` with continuous column :math:`u = i + \\tfrac12` whose first hit
    :math:`P` projects to column :math:`u'` of the other view,

    .. math::

        d = s\\,(u_R - u_L), \\qquad x_R = x_L + s\\,d,

    with :math:`s` the rig's ``disparity_sign``, so :math:`d > 0` for points at finite depth
    under both conventions. Depth is planar depth :math:`z = \\hat{z}\\cdot(P - O)` in the
    pixel's own camera.

    Parameters
    ----------
    points : numpy.ndarray, shape (H, W, 3)
        World-space first-hit points of ``view``.
    hit : numpy.ndarray, shape (H, W), bool
        Whether the pixel's ray hit the scene.
    rig : StereoRig
    view : {"left", "right"}

    Returns
    -------
    dict
        ``disparity`` (px, float64), ``depth`` (m, float64), ``hit_depth`` (the depth at
        every hit pixel, valid or not), ``valid`` (bool),
        ``other_u``/``other_v``/``other_z`` (the projection into the other camera) and
        ``vertical_error`` (px, :math:`|v' - v|`, zero for a rectified rig). Float fields are 0
        where not ``valid``.
    """
    other = VIEWS[1 - VIEWS.index(view)]
    height, width = hit.shape
    u_self = np.arange(width)[None, :] + 0.5
    v_self = np.arange(height)[:, None] + 0.5
    depth = (np.asarray(points, dtype=np.float64) - rig.origin(view)) @ rig.frame(view)[2]
    u_o, v_o, z_o = rig.project(points, other)
    u_left, u_right = (u_self, u_o) if view == "left" else (u_o, u_self)
    disparity = rig.disparity_sign * (u_right - u_left)
    col = u_o - 0.5  # column index coordinate in the other image
    with np.errstate(invalid="ignore"):
        valid = (
            hit
            & np.isfinite(disparity)
            & np.isfinite(depth)
            & (depth > 0)
            & (z_o > 0)
            & (col >= 0)
            & (col <= width - 1)
            & (disparity > 0)
        )
    vertical = np.abs(v_o - v_self)

    def clean(a):
        return np.where(valid, a, 0.0)

    with np.errstate(invalid="ignore"):
        seen = hit & np.isfinite(depth) & (depth > 0)
    return {
        "disparity": clean(disparity),
        "depth": clean(depth),
        "hit_depth": np.where(seen, depth, 0.0),
        "valid": valid,
        "other_u": clean(u_o),
        "other_v": clean(v_o),
        "other_z": clean(z_o),
        "vertical_error": clean(vertical),
    }


def occlusion_mask(corr: dict, other_depth, other_hit, *, rel_tol: float = 0.01) -> np.ndarray:
    """Left-right depth check: correspondences hidden in the other view.

    A valid pixel is occluded when the other view's pixel containing its correspondence
    (nearest-pixel lookup) sees a surface closer than the projected depth by more than
    ``rel_tol`` relative, or sees nothing. Pixels at depth edges may be flagged too.
    """
    valid = corr["valid"]
    height, width = valid.shape
    cols = np.clip(np.floor(corr["other_u"]).astype(np.int64), 0, width - 1)
    rows = np.broadcast_to(np.arange(height)[:, None], valid.shape)
    seen_depth = other_depth[rows, cols]
    seen_hit = other_hit[rows, cols]
    hidden = ~seen_hit | (seen_depth < corr["other_z"] * (1.0 - rel_tol))
    return valid & hidden


def compute_ground_truth(prepared, *, attrs: dict | None = None) -> xr.Dataset:
    """Ground truth of both views of a prepared scene under its rig (paper Sec. 3.1).

    The renderer traces one ray through each pixel centre
    (:meth:`~stereovar.renderers.base.PreparedScene.trace`); everything else is
    renderer-neutral: each float32 hit is re-intersected in float64 with its tangent plane
    (:func:`refine_hits`) and projected into the other camera (:func:`correspondence`),

    .. math:: d = s\\,(u_R - u_L), \\qquad x_R = x_L + s\\,d,

    and the left-right depth check flags occlusions (:func:`occlusion_mask`).

    Parameters
    ----------
    prepared : stereovar.renderers.base.PreparedScene
        A scene compiled by a renderer, with its rig.
    attrs : dict, optional
        Extra provenance attributes (scene name, digest, variant, ...).

    Returns
    -------
    xarray.Dataset
        On dims ``(view, y, x)``: ``disparity`` [px, float32, > 0 where valid],
        ``depth`` [m, planar, float32], ``material`` (uint8 code into
        :data:`MATERIAL_CLASSES`), ``glass``, ``valid`` and ``occluded`` (bool) and
        ``shape_index`` (int16, -1 for background). Attributes record the convention,
        ``disparity_sign``, ``baseline_m``, ``focal_px``, ``fov_deg``, ``width``, ``height``.
    """
    rig = prepared.rig
    codes, shape_ids = prepared.shape_materials()
    codes = np.asarray(codes, dtype=np.uint8)
    traced = {}
    for view in VIEWS:
        hit, points, normals, shape_index = prepared.trace(view)
        points = refine_hits(rig.origin(view), rig.pixel_rays(view), points, normals)
        traced[view] = (hit, points, shape_index)
    corr = {view: correspondence(traced[view][1], traced[view][0], rig, view) for view in VIEWS}
    depth = {view: corr[view]["hit_depth"] for view in VIEWS}
    fields = {k: [] for k in ("disparity", "depth", "material", "valid", "occluded", "shape_index")}
    vertical = 0.0
    for view in VIEWS:
        hit, _, shape_index = traced[view]
        other = VIEWS[1 - VIEWS.index(view)]
        c = corr[view]
        fields["disparity"].append(c["disparity"].astype(np.float32))
        fields["depth"].append(depth[view].astype(np.float32))
        fields["material"].append(
            np.where(hit, codes[np.clip(shape_index, 0, None)], 0).astype(np.uint8)
        )
        fields["valid"].append(c["valid"])
        fields["occluded"].append(occlusion_mask(c, depth[other], traced[other][0]))
        fields["shape_index"].append(shape_index.astype(np.int16))
        if c["valid"].any():
            vertical = max(vertical, float(c["vertical_error"][c["valid"]].max()))
    dims = ("view", "y", "x")
    coords = {"view": list(VIEWS), **pixel_coords(rig.height, rig.width)}
    material = np.stack(fields["material"])
    glass_code = MATERIAL_CLASSES.index("glass")
    ds = xr.Dataset(
        {
            "disparity": (
                dims,
                np.stack(fields["disparity"]),
                {
                    "units": "px",
                    "long_name": "disparity magnitude; x_R = x_L + disparity_sign * disparity",
                },
            ),
            "depth": (
                dims,
                np.stack(fields["depth"]),
                {
                    "units": "m",
                    "long_name": "planar depth along the optical axis",
                },
            ),
            "material": (
                dims,
                material,
                {
                    "long_name": "material class of the first hit",
                    "flag_values": list(range(len(MATERIAL_CLASSES))),
                    "flag_meanings": " ".join(MATERIAL_CLASSES),
                },
            ),
            "glass": (dims, material == glass_code, {"long_name": "glass (dielectric BSDF)"}),
            "valid": (
                dims,
                np.stack(fields["valid"]),
                {
                    "long_name": "hit, finite, and correspondence inside the other image",
                },
            ),
            "occluded": (
                dims,
                np.stack(fields["occluded"]),
                {
                    "long_name": "correspondence hidden in the other view (left-right depth check)",
                },
            ),
            "shape_index": (
                dims,
                np.stack(fields["shape_index"]),
                {
                    "long_name": "index of the first-hit shape; see attrs shape_ids; -1 background",
                },
            ),
        },
        coords=coords,
    )
    ds.attrs.update(
        {
            "convention": rig.convention,
            "disparity_sign": rig.disparity_sign,
            "correspondence": "x_R = x_L + disparity_sign * disparity",
            "baseline_m": rig.baseline_m,
            "focal_px": rig.focal_px,
            "fov_deg": rig.fov_deg,
            "width": rig.width,
            "height": rig.height,
            "material_classes": list(MATERIAL_CLASSES),
            "shape_ids": shape_ids,
            "max_vertical_disparity_px": vertical,
            **(attrs or {}),
        }
    )
    return ds


def summarize_ground_truth(ds: xr.Dataset, view: str = "left") -> dict:
    """Per-scene summary of one view: glass fraction, valid fraction and disparity range.

    The glass fraction is over all pixels of the view; the disparity statistics are over its
    valid pixels.
    """
    v = ds.sel(view=view)
    valid = v["valid"].values
    disp = v["disparity"].values[valid]
    n = valid.size
    material = v["material"].values
    row = {
        "glass_fraction": float(v["glass"].values.mean()),
        "valid_fraction": float(valid.mean()),
        "occluded_fraction": float(v["occluded"].values.mean()),
        "disparity_min_px": float(disp.min()) if disp.size else float("nan"),
        "disparity_median_px": float(np.median(disp)) if disp.size else float("nan"),
        "disparity_max_px": float(disp.max()) if disp.size else float("nan"),
    }
    for code, name in enumerate(MATERIAL_CLASSES):
        row[f"{name}_fraction"] = float((material == code).sum() / n)
    return row
