"""Cross-view alignment by the ground-truth disparity (paper Sec. 2.2, Eq. 2)."""

from __future__ import annotations

import numpy as np
import xarray as xr


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
    xs = np.arange(width)[None, :] + sign * d
    with np.errstate(invalid="ignore"):
        omega = np.isfinite(d) & (d > 0) & (xs >= 0) & (xs <= width - 1)
    if valid is not None:
        omega &= np.asarray(valid, dtype=bool)
    xs = np.where(omega, xs, 0.0)
    x0 = np.minimum(np.floor(xs).astype(np.int64), width - 2 if width > 1 else 0)
    t = xs - x0
    rows = np.broadcast_to(np.arange(height)[:, None], (height, width))
    x1 = np.minimum(x0 + 1, width - 1)
    t = t.reshape(t.shape + (1,) * (right.ndim - 2))
    warped = (1.0 - t) * right[rows, x0] + t * right[rows, x1]
    mask = omega.reshape(omega.shape + (1,) * (right.ndim - 2))
    return np.where(mask, warped, 0.0).astype(np.result_type(right.dtype, np.float32)), omega
