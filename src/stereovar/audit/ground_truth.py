"""Ground truth of an imported stereo frame, in the project's ground-truth store contract.

The files give the left view's disparity (or depth with the focal length and baseline), the
right view's optionally, and optionally a glass mask or a segmentation map. Everything is
turned into the contract of :func:`stereovar.ground_truth.compute_ground_truth` (dims
``(view, y, x)``; ``disparity``, ``depth``, ``material``, ``glass``, ``valid``,
``occluded``), so the warp, the statistics and the intervention read it unchanged.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..ground_truth import MATERIAL_CLASSES
from ..io.renders import pixel_coords
from ..rig import VIEWS

CONVENTIONS = {"paper": 1, "conventional": -1}
"""Disparity sign :math:`s` of each convention: :math:`x_R = x_L + s\\,d`."""

GLASS = MATERIAL_CLASSES.index("glass")
UNKNOWN = MATERIAL_CLASSES.index("background")

NO_MATERIAL_MASK = "no material mask given"
"""Reason of the glass and non_glass rows of an audit without a glass mask."""


def disparity_from_depth(depth, *, focal_px: float, baseline_m: float) -> np.ndarray:
    r"""Disparity of a rectified pair from planar depth (paper Sec. 3.1).

    .. math:: d = \frac{f\,B}{z}

    with :math:`f` the focal length in pixels and :math:`B` the baseline; non-positive or
    non-finite depth gives NaN (invalid).
    """
    z = np.asarray(depth, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.isfinite(z) & (z > 0), focal_px * baseline_m / z, np.nan)


def usable_disparity(disparity, *, sign: int) -> np.ndarray:
    """Pixels whose disparity magnitude is finite, positive and lands inside the other image.

    .. math:: \\{x : d(x) \\text{ finite},\\ d(x) > 0,\\ 0 \\le x + s\\,d(x) \\le W - 1\\}

    (``sign`` :math:`s` maps the left view into the right; use :math:`-s` for the right).
    """
    d = np.asarray(disparity, dtype=np.float64)
    target = np.arange(d.shape[1])[None, :] + sign * d
    with np.errstate(invalid="ignore"):
        return np.isfinite(d) & (d > 0) & (target >= 0) & (target <= d.shape[1] - 1)


def forward_warp(disparity, valid, *, sign: int) -> tuple[np.ndarray, np.ndarray]:
    r"""The other view's disparity and this view's occlusions by forward warping with a
    z-buffer.

    Each valid pixel lands on column :math:`\mathrm{round}(x + s\,d)` of the other view;
    where several land on one pixel the largest disparity (the nearest surface) wins. A
    pixel is occluded when a nearer one (more than 1 px of disparity larger) lands on its
    target.

    Returns
    -------
    other : numpy.ndarray, float64 (H, W)
        The other view's disparity magnitude, 0 where nothing lands.
    occluded : numpy.ndarray of bool (H, W)
    """
    d = np.asarray(disparity, dtype=np.float64)
    height, width = d.shape
    rows, cols = np.nonzero(valid)
    target = np.clip(np.rint(cols + sign * d[rows, cols]).astype(np.int64), 0, width - 1)
    other = np.zeros((height, width))
    np.maximum.at(other, (rows, target), d[rows, cols])
    occluded = np.zeros((height, width), dtype=bool)
    occluded[rows, cols] = d[rows, cols] < other[rows, target] - 1.0
    return other, occluded


def left_right_occlusion(disp_left, disp_right, valid_left, *, sign: int) -> np.ndarray:
    r"""Left-right consistency: a left pixel is occluded when the right view's disparity at
    its correspondence differs by more than 1 px.

    .. math:: |d_L(x) - d_R(\mathrm{round}(x + s\,d_L(x)))| > 1
    """
    d = np.asarray(disp_left, dtype=np.float64)
    rows, cols = np.nonzero(valid_left)
    target = np.clip(np.rint(cols + sign * d[rows, cols]).astype(np.int64), 0, d.shape[1] - 1)
    occluded = np.zeros(d.shape, dtype=bool)
    other = np.asarray(disp_right, dtype=np.float64)[rows, target]
    with np.errstate(invalid="ignore"):
        occluded[rows, cols] = ~(np.abs(d[rows, cols] - other) <= 1.0)
    return occluded


def imported_ground_truth(
    disparity_left,
    *,
    sign: int,
    disparity_right=None,
    depth=None,
    glass=None,
    material_source: str | None = None,
    attrs: dict | None = None,
) -> tuple[xr.Dataset, dict]:
    """The ground-truth store of one imported frame, and its counts of invalid pixels.

    Parameters
    ----------
    disparity_left : array_like (H, W)
        Disparity magnitude of the left view in px (:math:`x_R = x_L + s\\,d`); NaN, Inf,
        zero and negative values are invalid.
    sign : {1, -1}, keyword-only
        The convention's :math:`s` (:data:`CONVENTIONS`).
    disparity_right : array_like (H, W), optional
        The right view's (:math:`x_L = x_R - s\\,d`); by default forward-warped from the
        left one (:func:`forward_warp`).
    depth : dict, optional
        View to planar depth in m (absent views are 0: unknown).
    glass : array_like of bool (H, W), optional
        The left view's glass mask; None: no material mask (``glass`` all False and the
        ``material_mask`` attr ``none``).
    material_source : str, optional
        Where the glass mask came from (attr ``material_mask``).
    attrs : dict, optional
        Provenance (frame name, source files and digests, ...).

    Returns
    -------
    ds : xarray.Dataset
    counts : dict
        ``invalid_disparity`` (non-finite, zero or negative left disparity),
        ``outside`` (correspondence outside the right image) and ``valid`` pixels.
    """
    dl = np.asarray(disparity_left, dtype=np.float64)
    height, width = dl.shape
    with np.errstate(invalid="ignore"):
        bad = ~(np.isfinite(dl) & (dl > 0))
    valid_l = usable_disparity(dl, sign=sign)
    if disparity_right is None:
        dr, occluded_l = forward_warp(dl, valid_l, sign=sign)
        right_source = "forward-warped from the left view"
    else:
        dr = np.asarray(disparity_right, dtype=np.float64)
        occluded_l = left_right_occlusion(dl, dr, valid_l, sign=sign)
        right_source = "file"
    valid_r = usable_disparity(dr, sign=-sign)
    occluded_r = (
        left_right_occlusion(dr, dl, valid_r, sign=-sign)
        if disparity_right is not None
        else forward_warp(dr, valid_r, sign=-sign)[1]
    )
    depth = depth or {}
    glass_l = np.zeros((height, width), dtype=bool) if glass is None else np.asarray(glass, bool)
    material_l = np.where(glass_l, GLASS, UNKNOWN).astype(np.uint8)

    def field(values, valid):
        return np.where(valid, values, 0.0).astype(np.float32)

    dims = ("view", "y", "x")
    depth_fields = [
        np.nan_to_num(np.asarray(depth.get(v, np.zeros((height, width))), dtype=np.float64))
        for v in VIEWS
    ]
    ds = xr.Dataset(
        {
            "disparity": (
                dims,
                np.stack([field(dl, valid_l), field(dr, valid_r)]),
                {
                    "units": "px",
                    "long_name": "disparity magnitude; x_R = x_L + disparity_sign * disparity",
                },
            ),
            "depth": (
                dims,
                np.stack([np.clip(z, 0, None).astype(np.float32) for z in depth_fields]),
                {"units": "m", "long_name": "planar depth (0: not given)"},
            ),
            "material": (
                dims,
                np.stack([material_l, np.full_like(material_l, UNKNOWN)]),
                {
                    "long_name": "material class (imported: glass where masked, else unknown)",
                    "flag_values": list(range(len(MATERIAL_CLASSES))),
                    "flag_meanings": " ".join(MATERIAL_CLASSES),
                },
            ),
            "glass": (
                dims,
                np.stack([glass_l, np.zeros_like(glass_l)]),
                {"long_name": "glass (from the audit's material mask)"},
            ),
            "valid": (
                dims,
                np.stack([valid_l, valid_r]),
                {"long_name": "finite positive disparity landing inside the other image"},
            ),
            "occluded": (
                dims,
                np.stack([occluded_l, occluded_r]),
                {"long_name": "correspondence hidden in the other view"},
            ),
        },
        coords={"view": list(VIEWS), **pixel_coords(height, width)},
    )
    ds.attrs.update(
        {
            "convention": "paper" if sign == 1 else "conventional",
            "disparity_sign": int(sign),
            "correspondence": "x_R = x_L + disparity_sign * disparity",
            "width": int(width),
            "height": int(height),
            "material_classes": list(MATERIAL_CLASSES),
            "material_mask": material_source if glass is not None else "none",
            "right_disparity": right_source,
            **(attrs or {}),
        }
    )
    counts = {
        "invalid_disparity": int(bad.sum()),
        "outside": int((~bad & ~valid_l).sum()),
        "valid": int(valid_l.sum()),
    }
    return ds, counts
