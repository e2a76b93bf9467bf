"""Cross-view alignment by the ground-truth disparity (paper Sec. 2.2, Eq. 2).

:func:`warp_right_to_left` warps any right-view field; :func:`align_variance` warps the right
variance field and builds the valid set :math:`\\Omega` of Eq. 3.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .regions import as_field, valid_set


def warp_right_to_left(right, disparity, *, sign: int = 1, valid=None):
    """Bring a right-view field into left-view coordinates by bilinear interpolation along x.

    .. math::

        \\hat f_{R\\to L}(x, y) = f_R\\bigl(x + s\\,d(x, y),\\, y\\bigr)

    (Eq. 2, with :math:`s = +1` for the paper's :math:`x_R = x_L + d` convention and
    :math:`s = -1` for the conventional rig). Pixel ``x`` is masked out of the valid set
    :math:`\\Omega` when :math:`x + s\\,d` falls outside ``[0, W - 1]``, when :math:`d` is
    non-positive or non-finite, or when ``valid`` is False there.

    Parameters
    ----------
    right : numpy.ndarray or xarray.DataArray, shape (H, W, ...)
        Right-view field; with xarray, dims ``y`` and ``x`` are required and any other dims
        (e.g. ``channel``) are carried along.
    disparity : numpy.ndarray or xarray.DataArray, shape (H, W)
        Left-view disparity magnitude in pixels.
    sign : {1, -1}, keyword-only
        The ground truth's ``disparity_sign``.
    valid : array_like of bool, shape (H, W), optional
        Left-view validity (e.g. the ground truth's ``valid``).

    Returns
    -------
    warped : same type as ``right``
        The field in left coordinates; 0 outside :math:`\\Omega`.
    omega : same type as ``disparity`` (bool)
        The valid set :math:`\\Omega`.
    """
    if sign not in (1, -1):
        raise ValueError(f"sign must be +1 or -1, got {sign}")
    if isinstance(right, xr.DataArray):
        extra = [d for d in right.dims if d not in ("y", "x")]
        r = right.transpose("y", "x", *extra)
        d = disparity.transpose("y", "x") if isinstance(disparity, xr.DataArray) else disparity
        v = valid.transpose("y", "x") if isinstance(valid, xr.DataArray) else valid
        w, om = warp_right_to_left(
            r.values, np.asarray(d), sign=sign, valid=None if v is None else np.asarray(v)
        )
        warped = r.copy(data=w)
        omega = xr.DataArray(
            om, dims=("y", "x"), coords={k: r.coords[k] for k in ("y", "x") if k in r.coords}
        )
        return warped.transpose(*right.dims), omega
    right = np.asarray(right)
    d = np.asarray(disparity, dtype=np.float64)
    height, width = right.shape[:2]
    if d.shape != (height, width):
        raise ValueError(f"disparity shape {d.shape} does not match the field's {(height, width)}")
    omega = valid_set(d, sign=sign, valid=valid)
    xs = np.where(omega, np.arange(width)[None, :] + sign * d, 0.0)
    x0 = np.minimum(np.floor(xs).astype(np.int64), width - 2 if width > 1 else 0)
    t = xs - x0
    rows = np.broadcast_to(np.arange(height)[:, None], (height, width))
    x1 = np.minimum(x0 + 1, width - 1)
    t = t.reshape(t.shape + (1,) * (right.ndim - 2))
    warped = (1.0 - t) * right[rows, x0] + t * right[rows, x1]
    mask = omega.reshape(omega.shape + (1,) * (right.ndim - 2))
    return np.where(mask, warped, 0.0).astype(np.result_type(right.dtype, np.float32)), omega


def warp_finite(right, disparity, *, sign: int, valid=None, finite=None):
    """Eq. 2 of a right-view field with non-finite pixels: their values and their spoiling.

    .. math:: \\hat f_{R\\to L}(x, y) = f_R\\bigl(x + s\\,d(x, y),\\, y\\bigr)

    with non-finite right pixels (or those ``finite`` marks False) read as 0.

    Returns
    -------
    warped : numpy.ndarray, float64 (H, W)
        0 outside the geometric valid set.
    omega : numpy.ndarray of bool (H, W)
        The geometric valid set (:func:`warp_right_to_left`).
    clean : numpy.ndarray of bool (H, W)
        No right pixel with non-zero bilinear weight was non-finite.
    """
    right = np.asarray(right, dtype=np.float64)
    fin = np.isfinite(right)
    if finite is not None:
        fin &= np.asarray(finite, dtype=bool)
    warped, omega = warp_right_to_left(np.where(fin, right, 0.0), disparity, sign=sign, valid=valid)
    if fin.all():
        return warped, omega, np.ones(omega.shape, dtype=bool)
    spoiled, _ = warp_right_to_left((~fin).astype(np.float64), disparity, sign=sign)
    return warped, omega, spoiled == 0


def align_variance(
    sigma_left, sigma_right, ground_truth_left, *, sign: int, finite_left=None, finite_right=None
) -> dict:
    """Warp the right variance field into the left view and build the valid set (Eq. 2).

    .. math:: \\hat\\sigma_{R\\to L}^2(x, y) = \\sigma_R^2\\bigl(x + s\\,d(x, y),\\, y\\bigr)

    Parameters
    ----------
    sigma_left, sigma_right, ground_truth_left, sign, finite_left, finite_right
        As in :func:`stereovar.statistics.rows.correlation_rows` (reference:
        ``tests/reference/correlation.py``): the variance fields, the left view of the
        ground truth (``disparity``, ``valid``), its ``disparity_sign`` and the variance
        stores' ``finite`` flags.

    Returns
    -------
    dict
        ``warped`` (float64, 0 outside the geometric valid set), ``omega_geometry`` (the warp's
        valid set from the ground truth alone), ``usable`` (left value finite and warped right
        value built only from finite right pixels) and ``omega`` (both: the :math:`\\Omega` of
        Eq. 3).
    """
    left = as_field(sigma_left).astype(np.float64)
    right = as_field(sigma_right).astype(np.float64)
    if left.shape != right.shape or left.ndim != 2:
        raise ValueError(f"fields must share one (H, W) shape, got {left.shape}, {right.shape}")
    fin_left = np.isfinite(left)
    if finite_left is not None:
        fin_left &= as_field(finite_left).astype(bool)
    warped, omega_gt, clean = warp_finite(
        right,
        as_field(ground_truth_left["disparity"]),
        sign=sign,
        valid=as_field(ground_truth_left["valid"]),
        finite=None if finite_right is None else as_field(finite_right).astype(bool),
    )
    # a warped value is clean when no neighbour with non-zero weight is non-finite
    usable = fin_left & clean
    return {
        "warped": warped,
        "omega_geometry": omega_gt,
        "usable": usable,
        "omega": omega_gt & usable,
    }
