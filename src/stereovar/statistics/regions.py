"""The valid set :math:`\\Omega` and the material regions, defined once (paper Sec. 2.2, 2.3).

Table 1's correlations, Table 2's mean variances and the intervention's metrics (Sec. 3.4) all
take their pixel sets from here.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

REGIONS = ("all", "non_glass", "glass")
"""The regions of every table: :math:`\\Omega`, :math:`\\Omega \\setminus G`,
:math:`\\Omega \\cap G`."""


def as_field(a) -> np.ndarray:
    """A per-pixel field as a numpy array; DataArrays are put in (y, x) order."""
    if isinstance(a, xr.DataArray):
        if set(a.dims) != {"y", "x"}:
            raise ValueError(
                f"expected a field on dims (y, x), got {a.dims}; select one view, "
                "e.g. .sel(view='left')"
            )
        return a.transpose("y", "x").values
    return np.asarray(a)


def valid_set(disparity, *, sign: int, valid=None) -> np.ndarray:
    """The geometric valid set of the warp (paper Sec. 2.2).

    .. math::

        \\Omega_{\\text{geom}} = \\{(x, y) : d(x, y) \\text{ finite},\\ d(x, y) > 0,\\
            0 \\le x + s\\,d(x, y) \\le W - 1\\} \\cap \\text{valid}

    Parameters
    ----------
    disparity : array_like, shape (H, W)
        Left-view disparity magnitude in pixels.
    sign : {1, -1}, keyword-only
        The ground truth's ``disparity_sign``.
    valid : array_like of bool, shape (H, W), optional
        Left-view validity (the ground truth's ``valid``).

    Returns
    -------
    numpy.ndarray of bool, shape (H, W)

    Examples
    --------
    One row of width 5 and the paper's convention (:math:`s = +1`): pixel 0 matches
    :math:`x_R = 1`; pixel 1's disparity is 0, pixel 2's NaN; pixel 3 matches
    :math:`x_R = 5`, outside the image; pixel 4 matches :math:`x_R = 4.5`, also outside.

    >>> import numpy as np
    >>> valid_set(np.array([[1.0, 0.0, np.nan, 2.0, 0.5]]), sign=1).tolist()
    [[True, False, False, False, False]]

    On the conventional rig (:math:`s = -1`) pixels 3 and 4 match :math:`x_R = 1` and 3.5,
    and pixel 0 matches :math:`x_R = -1`, outside:

    >>> valid_set(np.array([[1.0, 0.0, np.nan, 2.0, 0.5]]), sign=-1).tolist()
    [[False, False, False, True, True]]
    """
    d = np.asarray(disparity, dtype=np.float64)
    xs = np.arange(d.shape[1])[None, :] + sign * d
    with np.errstate(invalid="ignore"):
        omega = np.isfinite(d) & (d > 0) & (xs >= 0) & (xs <= d.shape[1] - 1)
    if valid is not None:
        omega &= np.asarray(valid, dtype=bool)
    return omega


def region_masks(ground_truth_left, omega, *, regions=REGIONS) -> dict:
    """The valid set restricted by the ground-truth glass mask (paper Sec. 2.3).

    .. math::

        \\Omega_{\\text{all}} = \\Omega, \\quad
        \\Omega_{\\text{non\\_glass}} = \\Omega \\setminus G, \\quad
        \\Omega_{\\text{glass}} = \\Omega \\cap G,

    with :math:`G` the left view's ``glass`` mask.

    Parameters
    ----------
    ground_truth_left : xarray.Dataset or mapping
        The left view of the ground truth (``gt.sel(view="left")``); only ``glass`` is used.
    omega : array_like of bool or xarray.DataArray, shape (H, W)
        The valid set :math:`\\Omega`.
    regions : sequence of str, keyword-only
        Which of :data:`REGIONS` to return, in this order.

    Returns
    -------
    dict
        Region name to bool mask, DataArrays when ``omega`` is one.
    """
    glass = as_field(ground_truth_left["glass"]).astype(bool)
    om = as_field(omega).astype(bool)
    if glass.shape != om.shape:
        raise ValueError(f"glass mask shape {glass.shape} differs from omega's {om.shape}")
    unknown = [r for r in regions if r not in REGIONS]
    if unknown:
        raise ValueError(f"unknown regions {unknown}; use some of {REGIONS}")
    every = {"all": om, "non_glass": om & ~glass, "glass": om & glass}
    masks = {r: every[r] for r in regions}
    if isinstance(omega, xr.DataArray):
        template = omega.transpose("y", "x")
        masks = {k: template.copy(data=v) for k, v in masks.items()}
    return masks
