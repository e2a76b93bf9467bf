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

    (paper Sec. 2.2, Eq. 2, with :math:`s = +1` for the paper's :math:`x_R = x_L + d` convention and
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

    Examples
    --------
    A right field that grows by 10 per pixel, :math:`f_R(x) = 10x` on one row of width 5,
    and a constant disparity of 1.5 px. With the paper's convention (:math:`s = +1`) left pixel
    :math:`x` reads :math:`f_R(x + 1.5) = 10x + 15` (bilinear between two right pixels) while
    :math:`x + 1.5 \\le 4`; pixels 3 and 4 match outside the right image and leave
    :math:`\\Omega`:

    >>> import numpy as np
    >>> right = 10.0 * np.arange(5.0)[None, :]
    >>> disparity = np.full((1, 5), 1.5)
    >>> warped, omega = warp_right_to_left(right, disparity, sign=1)
    >>> warped.tolist(), omega.tolist()
    ([[15.0, 25.0, 35.0, 0.0, 0.0]], [[True, True, True, False, False]])

    The conventional rig (:math:`x_R = x_L - d`, :math:`s = -1`) reads :math:`10x - 15`,
    defined from :math:`x = 2` on; a non-positive or non-finite disparity is never valid:

    >>> warped, omega = warp_right_to_left(right, disparity, sign=-1)
    >>> warped.tolist(), omega.tolist()
    ([[0.0, 0.0, 5.0, 15.0, 25.0]], [[False, False, True, True, True]])
    >>> disparity[0, 2:] = [0.0, np.nan, -1.0]
    >>> warp_right_to_left(right, disparity, sign=1)[1].tolist()
    [[True, True, False, False, False]]
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
    d = np.asarray(disparity)
    if d.shape != right.shape[:2]:
        raise ValueError(f"disparity shape {d.shape} does not match the field's {right.shape[:2]}")
    plan = WarpPlan(d, sign=sign, valid=valid)
    return plan.apply(right), plan.omega


class WarpPlan:
    """Eq. 2's sampling positions for one disparity map, applied to any number of fields.

    .. math::

        \\hat f_{R\\to L}(x, y) = (1 - t) f_R(x_0, y) + t f_R(x_0 + 1, y), \\quad
        x_0 = \\lfloor x + s\\,d \\rfloor,\\ t = x + s\\,d - x_0

    on :math:`\\Omega_{\\text{geom}}` (:func:`~stereovar.statistics.regions.valid_set`).
    The variance fields, the seed means, the split halves, the seed subsets and the sensor
    fields of a scene share one disparity, so they share one plan.

    Parameters
    ----------
    disparity : array_like, shape (H, W)
    sign : {1, -1}, keyword-only
    valid : array_like of bool, shape (H, W), optional
    """

    def __init__(self, disparity, *, sign: int = 1, valid=None):
        if sign not in (1, -1):
            raise ValueError(f"sign must be +1 or -1, got {sign}")
        d = np.asarray(disparity, dtype=np.float64)
        height, width = d.shape
        self.shape = (height, width)
        self.omega = valid_set(d, sign=sign, valid=valid)
        self.index = np.flatnonzero(self.omega)
        xs = (self.index % width) + sign * d.reshape(-1)[self.index]
        x0 = np.minimum(np.floor(xs).astype(np.int64), width - 2 if width > 1 else 0)
        row = self.index - self.index % width
        self.first = row + x0
        self.second = row + np.minimum(x0 + 1, width - 1)
        self.weight = xs - x0
        self._cache: dict = {}

    def sample(self, right, pixels=None) -> np.ndarray:
        """Eq. 2 at some left pixels of :math:`\\Omega_{\\text{geom}}`.

        Parameters
        ----------
        right : numpy.ndarray, shape (..., H, W)
            Right-view fields, any leading dims (e.g. seed subsets).
        pixels : numpy.ndarray of int, optional
            Flat indices of left pixels inside :attr:`omega`, any order; all of
            :attr:`index` when omitted. The taps for an index array are cached.

        Returns
        -------
        numpy.ndarray, shape (..., n), float64

        Raises
        ------
        ValueError
            A pixel lies outside the valid set.
        """
        first, second, weight, rest = self._taps(pixels)
        flat = np.asarray(right).reshape(*np.shape(right)[:-2], -1)
        out = np.multiply(np.take(flat, first, axis=-1), rest)
        out += weight * np.take(flat, second, axis=-1)
        return out

    def _taps(self, pixels) -> tuple:
        key = None if pixels is None else id(pixels)
        hit = self._cache.get(key)
        if hit is not None:
            return hit[1]
        if pixels is None:
            taps = (self.first, self.second, self.weight, 1.0 - self.weight)
        else:
            pixels = np.asarray(pixels)
            found = np.searchsorted(self.index, pixels)
            if found.size and (
                found.max() >= self.index.size or not np.array_equal(self.index[found], pixels)
            ):
                raise ValueError("pixels outside the warp's valid set have no Eq. 2 sample")
            weight = self.weight[found]
            taps = (self.first[found], self.second[found], weight, 1.0 - weight)
        self._cache[key] = (pixels, taps)
        return taps

    def field(self, right) -> WarpedField:
        """The warp of a right field (H, W), sampled lazily (:class:`WarpedField`)."""
        return WarpedField(self, right)

    def apply(self, right) -> np.ndarray:
        """Eq. 2 of a right field (H, W, ...) into left coordinates, 0 outside
        :math:`\\Omega_{\\text{geom}}`; dtype at least float32."""
        right = np.asarray(right)
        height, width = self.shape
        if right.shape[:2] != (height, width):
            raise ValueError(
                f"field shape {right.shape[:2]} does not match the disparity's {self.shape}"
            )
        extra = right.shape[2:]
        flat = right.reshape(height * width, -1)
        weight = self.weight[:, None]
        values = (1.0 - weight) * flat[self.first] + weight * flat[self.second]
        dtype = np.result_type(right.dtype, np.float32)
        out = np.zeros((height * width, flat.shape[1]), dtype=dtype)
        out[self.index] = values
        return out.reshape(height, width, *extra)


class WarpedField:
    """A right-view field warped by a :class:`WarpPlan`, computed only at the pixels asked
    for (:meth:`at`); ``numpy.asarray`` gives the whole field as
    :func:`~stereovar.statistics.fields.warp_field` would.

    Non-finite right pixels spoil the left pixels that give them a non-zero weight (NaN
    there), as in :func:`warp_finite`.
    """

    def __init__(self, plan: WarpPlan, right):
        self.plan = plan
        self.right = np.asarray(right)
        self.shape = plan.shape

    def at(self, index) -> np.ndarray:
        """float64 values at flat left pixels ``index`` (inside the plan's valid set)."""
        values = self.plan.sample(self.right, index)
        if np.isfinite(values.sum()):
            return values
        right = np.asarray(self.right, dtype=np.float64)
        finite = np.isfinite(right)
        values = self.plan.sample(np.where(finite, right, 0.0), index)
        spoiled = self.plan.sample((~finite).astype(np.float64), index)
        values[spoiled != 0] = np.nan
        return values

    def __array__(self, dtype=None, copy=None):
        out = np.full(self.shape[0] * self.shape[1], np.nan)
        out[self.plan.index] = self.at(self.plan.index)
        out = out.reshape(self.shape)
        return out if dtype is None else out.astype(dtype)


def warp_finite(right, disparity, *, sign: int, valid=None, finite=None, plan=None):
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
    plan = plan or WarpPlan(disparity, sign=sign, valid=valid)
    all_finite = bool(fin.all())
    warped = plan.apply(right if all_finite else np.where(fin, right, 0.0))
    if all_finite:
        return warped, plan.omega, np.ones(plan.omega.shape, dtype=bool)
    spoiled, _ = warp_right_to_left((~fin).astype(np.float64), disparity, sign=sign)
    return warped, plan.omega, spoiled == 0


def align_variance(
    sigma_left, sigma_right, ground_truth_left, *, sign: int, finite_left=None, finite_right=None
) -> dict:
    """Warp the right variance field into the left view and build the valid set (Eq. 2).

    .. math::

        \\hat\\sigma_{R\\to L}^2(x, y) = \\sigma_R^2\\bigl(x + s\\,d(x, y),\\, y\\bigr)

    (paper Sec. 2.2, Eq. 2), on the valid set :math:`\\Omega` of Eq. 3 (Sec. 2.3).

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

    Examples
    --------
    A right variance field that is the left one seen 2 px further right (paper convention,
    :math:`\\sigma_R^2(x + 2) = \\sigma_L^2(x)`): the warp by :math:`d = 2` recovers the left
    field on :math:`\\Omega`, the pixels whose match lies inside the right image. A NaN in the
    right field removes the left pixels that read it from ``omega`` (not from
    ``omega_geometry``):

    >>> import numpy as np
    >>> left = np.array([[1.0, 4.0, 2.0, 8.0, 5.0, 7.0]])
    >>> right = np.array([[0.0, 0.0, 1.0, 4.0, 2.0, 8.0]])
    >>> gt = {"disparity": np.full((1, 6), 2.0), "valid": np.ones((1, 6), bool)}
    >>> out = align_variance(left, right, gt, sign=1)
    >>> out["omega"].tolist()
    [[True, True, True, True, False, False]]
    >>> bool(np.array_equal(out["warped"][out["omega"]], left[out["omega"]]))
    True
    >>> right[0, 3] = np.nan
    >>> out = align_variance(left, right, gt, sign=1)
    >>> out["omega_geometry"].tolist(), out["omega"].tolist()
    ([[True, True, True, True, False, False]], [[True, False, True, True, False, False]])
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
