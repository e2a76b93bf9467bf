"""Cross-view Pearson correlation of variance fields (paper Sec. 2.3, Eq. 3, and Sec. 3.1).

:func:`pearson_over_mask` is Eq. 3 over any pixel set with its Fisher-z interval and test;
:func:`region_masks` restricts the valid set :math:`\\Omega` by the ground-truth glass mask;
:func:`correlation_rows` produces one scene's rows (region x warp / no warp).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from .warp import warp_right_to_left

REGIONS = ("all", "non_glass", "glass")
METHODS = ("warp", "no_warp")

Z_95 = 1.959963984540054
"""Two-sided 95% quantile of the standard normal, :math:`\\Phi^{-1}(0.975)`."""

NO_GLASS = "no glass pixels in the scene"
CONSTANT = "constant field in region"


def _field(a) -> np.ndarray:
    """A per-pixel field as a numpy array; DataArrays are put in (y, x) order."""
    if isinstance(a, xr.DataArray):
        if set(a.dims) != {"y", "x"}:
            raise ValueError(
                f"expected a field on dims (y, x), got {a.dims}; select one view, "
                "e.g. .sel(view='left')"
            )
        return a.transpose("y", "x").values
    return np.asarray(a)


def _undefined(n_pixels: int, n_nonfinite: int, reason: str) -> dict:
    nan = float("nan")
    return {
        "rho": nan,
        "n_pixels": int(n_pixels),
        "ci_low": nan,
        "ci_high": nan,
        "p_value": nan,
        "log10_p_value": nan,
        "n_nonfinite": int(n_nonfinite),
        "reason": reason,
    }


def log10_two_sided_normal_p(stat: float) -> float:
    """Base-10 log of the two-sided normal p-value :math:`2\\,\\Phi(-|z|)`, without underflow.

    .. math::

        p = \\operatorname{erfc}\\bigl(|z| / \\sqrt{2}\\bigr), \\qquad
        \\ln \\operatorname{erfc}(u) \\approx -u^2 - \\ln\\bigl(u \\sqrt{\\pi}\\bigr)
            + \\ln\\Bigl(1 - \\frac{1}{2u^2} + \\frac{3}{4u^4} - \\frac{15}{8u^6}\\Bigr)

    The asymptotic series is used where ``erfc`` would underflow (:math:`u > 20`, where it
    is accurate to better than 1e-9 relative), so p-values far below 1e-300 (the paper's
    ~9e5-pixel regions) keep a finite logarithm.
    """
    u = abs(float(stat)) / math.sqrt(2.0)
    if not math.isfinite(u):
        return -math.inf if math.isinf(u) else math.nan
    if u <= 20.0:
        return math.log10(math.erfc(u))
    inv = 1.0 / (u * u)
    series = 1.0 - 0.5 * inv + 0.75 * inv * inv - 1.875 * inv**3
    return (-u * u - math.log(u * math.sqrt(math.pi)) + math.log(series)) / math.log(10.0)


def pearson_over_mask(a, b, mask, *, min_pixels: int = 30) -> dict:
    """Pearson correlation of two fields over a pixel set, with Fisher-z interval and test.

    Over the :math:`n` pixels of ``mask`` where both fields are finite (paper Sec. 2.3,
    Eq. 3; significance as in Sec. 3.1),

    .. math::

        \\rho = \\frac{\\sum_i (a_i - \\bar a)(b_i - \\bar b)}
                     {\\sqrt{\\sum_i (a_i - \\bar a)^2 \\sum_i (b_i - \\bar b)^2}}, \\qquad
        z = \\operatorname{artanh} \\rho, \\quad s = \\frac{1}{\\sqrt{n - 3}},

        \\mathrm{CI}_{95} = \\bigl[\\tanh(z - 1.959964\\,s),\\ \\tanh(z + 1.959964\\,s)\\bigr],
        \\qquad p = 2\\,\\Phi\\bigl(-|z|\\sqrt{n - 3}\\bigr),

    accumulated in float64. ``log10_p_value`` is :math:`\\log_{10} p` from the log survival
    function, so it stays finite where :math:`p` underflows to 0 (it is :math:`-\\infty` only
    for :math:`|\\rho| = 1`).

    Parameters
    ----------
    a, b : array_like or xarray.DataArray
        The two fields (same shape; DataArrays on dims ``y`` and ``x``).
    mask : array_like of bool
        Pixel set (e.g. :math:`\\Omega` restricted to a region).
    min_pixels : int, keyword-only
        Fewest pixels for a defined result (at least 4).

    Returns
    -------
    dict
        ``rho``, ``n_pixels`` (pixels used), ``ci_low``, ``ci_high``, ``p_value``,
        ``log10_p_value``, ``n_nonfinite`` (pixels of ``mask`` dropped because ``a`` or ``b``
        is NaN or Inf) and ``reason``: ``""``, or why the correlation is undefined (fewer than
        ``min_pixels`` pixels, or a constant field), in which case the numbers are NaN.
    """
    if min_pixels < 4:
        raise ValueError(
            f"min_pixels must be at least 4 for the Fisher z interval, got {min_pixels}"
        )
    a, b, mask = _field(a), _field(b), _field(mask).astype(bool)
    if not a.shape == b.shape == mask.shape:
        raise ValueError(f"shapes differ: a {a.shape}, b {b.shape}, mask {mask.shape}")
    av = a[mask].astype(np.float64)
    bv = b[mask].astype(np.float64)
    ok = np.isfinite(av) & np.isfinite(bv)
    n_nonfinite = int(ok.size - ok.sum())
    av, bv = av[ok], bv[ok]
    n = int(av.size)
    if n < min_pixels:
        return _undefined(n, n_nonfinite, f"fewer than {min_pixels} valid pixels (n={n})")
    if av.min() == av.max() or bv.min() == bv.max():
        return _undefined(n, n_nonfinite, CONSTANT)
    da = av - av.mean()
    db = bv - bv.mean()
    da /= np.abs(da).max()  # Pearson is scale-invariant; this keeps the sums from overflowing
    db /= np.abs(db).max()
    sxx, syy, sxy = da @ da, db @ db, da @ db
    if not (sxx > 0 and syy > 0):
        return _undefined(n, n_nonfinite, CONSTANT)
    rho = float(np.clip(sxy / math.sqrt(sxx * syy), -1.0, 1.0))
    with np.errstate(divide="ignore"):
        z = float(np.arctanh(rho))
    se = 1.0 / math.sqrt(n - 3)
    stat = abs(z) / se
    return {
        "rho": rho,
        "n_pixels": n,
        "ci_low": float(np.tanh(z - Z_95 * se)),
        "ci_high": float(np.tanh(z + Z_95 * se)),
        "p_value": math.erfc(stat / math.sqrt(2.0)),
        "log10_p_value": log10_two_sided_normal_p(stat),
        "n_nonfinite": n_nonfinite,
        "reason": "",
    }


def region_masks(ground_truth_left, omega) -> dict:
    """The valid set restricted by the ground-truth glass mask (paper Sec. 2.3).

    .. math::

        \\Omega_{\\text{all}} = \\Omega, \\quad
        \\Omega_{\\neg\\text{glass}} = \\Omega \\setminus G, \\quad
        \\Omega_{\\text{glass}} = \\Omega \\cap G,

    with :math:`G` the left view's ``glass`` mask.

    Parameters
    ----------
    ground_truth_left : xarray.Dataset or mapping
        The left view of the ground truth (``gt.sel(view="left")``); only ``glass`` is used.
    omega : array_like of bool or xarray.DataArray, shape (H, W)
        The valid set :math:`\\Omega`.

    Returns
    -------
    dict
        ``{"all", "non_glass", "glass"}`` to bool masks, DataArrays when ``omega`` is one.
    """
    glass = _field(ground_truth_left["glass"]).astype(bool)
    om = _field(omega).astype(bool)
    if glass.shape != om.shape:
        raise ValueError(f"glass mask shape {glass.shape} differs from omega's {om.shape}")
    masks = {"all": om, "non_glass": om & ~glass, "glass": om & glass}
    if isinstance(omega, xr.DataArray):
        template = omega.transpose("y", "x")
        masks = {k: template.copy(data=v) for k, v in masks.items()}
    return masks


def correlation_rows(
    sigma_left,
    sigma_right,
    ground_truth_left,
    *,
    sign: int,
    finite_left=None,
    finite_right=None,
    min_pixels: int = 30,
) -> list[dict]:
    """One scene's cross-view correlations: region x (warp, no warp) (paper Sec. 2.3, 3.1).

    The right field is brought into left coordinates by Eq. 2
    (:func:`stereovar.warp.warp_right_to_left`) and correlated with the left field by Eq. 3,

    .. math::

        \\rho_{\\text{warp}} = \\mathrm{corr}\\bigl(\\sigma_L^2,\\,
            \\hat\\sigma_{R\\to L}^2\\bigr)\\big|_{\\Omega_r}, \\qquad
        \\rho_{\\text{no-warp}} = \\mathrm{corr}\\bigl(\\sigma_L^2(x, y),\\,
            \\sigma_R^2(x, y)\\bigr)\\big|_{\\Omega_r},

    for each region :math:`r` of :func:`region_masks`. :math:`\\Omega` is the warp's valid set
    (ground-truth ``valid``, :math:`d > 0`, correspondence inside the right image) further
    restricted to pixels whose left value is finite and whose warped right value is built only
    from finite right pixels (each neighbour with non-zero bilinear weight; a neighbour with
    zero weight does not enter the value). Both methods use this same :math:`\\Omega_r`, so
    the no-warp baseline differs from the warp only by the alignment; the no-warp row also
    drops the (rare) pixels whose unaligned right value is non-finite.

    Parameters
    ----------
    sigma_left, sigma_right : array_like or xarray.DataArray, shape (H, W)
        Variance fields :math:`\\sigma_L^2`, :math:`\\sigma_R^2` (Eq. 1).
    ground_truth_left : xarray.Dataset or mapping
        Left view of the ground truth: ``disparity``, ``valid``, ``glass``.
    sign : {1, -1}, keyword-only
        The ground truth's ``disparity_sign``.
    finite_left, finite_right : array_like of bool, shape (H, W), optional
        The variance stores' ``finite`` flags; non-finite field values are excluded as well.
    min_pixels : int, keyword-only
        Passed to :func:`pearson_over_mask`.

    Returns
    -------
    list of dict
        Rows in the order ``REGIONS`` x ``METHODS`` with keys ``region``, ``method``, ``rho``,
        ``n_pixels``, ``ci_low``, ``ci_high``, ``p_value``, ``log10_p_value``, ``n_nonfinite``
        (ground-truth-valid pixels of the region excluded because a render was NaN or Inf
        there) and ``reason`` (``""`` or why the row is NaN; a scene without glass pixels
        gives ``"no glass pixels in the scene"`` for both glass rows).
    """
    aligned = align_variance(
        sigma_left,
        sigma_right,
        ground_truth_left,
        sign=sign,
        finite_left=finite_left,
        finite_right=finite_right,
    )
    return rows_from_alignment(
        sigma_left,
        sigma_right,
        aligned,
        ground_truth_left["glass"],
        finite_right=finite_right,
        min_pixels=min_pixels,
    )


def align_variance(
    sigma_left, sigma_right, ground_truth_left, *, sign: int, finite_left=None, finite_right=None
) -> dict:
    """Warp the right variance field into the left view and build the valid set (Eq. 2).

    .. math:: \\hat\\sigma_{R\\to L}^2(x, y) = \\sigma_R^2\\bigl(x + s\\,d(x, y),\\, y\\bigr)

    Parameters
    ----------
    sigma_left, sigma_right, ground_truth_left, sign, finite_left, finite_right
        As in :func:`correlation_rows`.

    Returns
    -------
    dict
        ``warped`` (float64, 0 outside the geometric valid set), ``omega_geometry`` (the warp's
        valid set from the ground truth alone), ``usable`` (left value finite and warped right
        value built only from finite right pixels) and ``omega`` (both: the :math:`\\Omega` of
        Eq. 3).
    """
    left = _field(sigma_left).astype(np.float64)
    right = _field(sigma_right).astype(np.float64)
    if left.shape != right.shape or left.ndim != 2:
        raise ValueError(f"fields must share one (H, W) shape, got {left.shape}, {right.shape}")
    fin_left = np.isfinite(left)
    fin_right = np.isfinite(right)
    if finite_left is not None:
        fin_left &= _field(finite_left).astype(bool)
    if finite_right is not None:
        fin_right &= _field(finite_right).astype(bool)
    disparity = _field(ground_truth_left["disparity"])
    warped, omega_gt = warp_right_to_left(
        np.where(fin_right, right, 0.0),
        disparity,
        sign=sign,
        valid=_field(ground_truth_left["valid"]),
    )
    # a warped value is clean when no neighbour with non-zero weight is non-finite
    if fin_right.all():
        usable = fin_left
    else:
        spoiled, _ = warp_right_to_left((~fin_right).astype(np.float64), disparity, sign=sign)
        usable = fin_left & (spoiled == 0)
    return {
        "warped": warped,
        "omega_geometry": omega_gt,
        "usable": usable,
        "omega": omega_gt & usable,
    }


def rows_from_alignment(
    sigma_left, sigma_right, aligned: dict, glass, *, finite_right=None, min_pixels: int = 30
) -> list[dict]:
    """Correlation rows (region x method) from an :func:`align_variance` result (Eq. 3).

    See :func:`correlation_rows` for the rows and the shared :math:`\\Omega_r`.
    """
    left = _field(sigma_left).astype(np.float64)
    right = _field(sigma_right).astype(np.float64)
    glass = _field(glass).astype(bool)
    masks = region_masks({"glass": glass}, _field(aligned["omega"]).astype(bool))
    gt_masks = region_masks({"glass": glass}, _field(aligned["omega_geometry"]).astype(bool))
    usable = _field(aligned["usable"]).astype(bool)
    warped = _field(aligned["warped"]).astype(np.float64)
    fin_right = np.isfinite(right)
    if finite_right is not None:
        fin_right &= _field(finite_right).astype(bool)
    unaligned = np.where(fin_right, right, np.nan)
    has_glass = bool(glass.any())
    rows = []
    for region in REGIONS:
        excluded = int((gt_masks[region] & ~usable).sum())
        for method in METHODS:
            if region == "glass" and not has_glass:
                result = _undefined(0, 0, NO_GLASS)
            else:
                other = warped if method == "warp" else unaligned
                result = pearson_over_mask(left, other, masks[region], min_pixels=min_pixels)
                result["n_nonfinite"] += excluded
            rows.append({"region": region, "method": method, **result})
    return rows
