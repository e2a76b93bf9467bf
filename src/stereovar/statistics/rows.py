"""One scene's correlation rows: every region times every registered statistic (Eq. 3).

The rows are the contract of ``results/{renderer}/{estimator}/correlation/{scene}/spp{spp}.csv``
(:data:`CORRELATION_COLUMNS`).
"""

from __future__ import annotations

import numpy as np

from .correlation import NO_GLASS, RESULT_KEYS, undefined_result
from .regions import REGIONS, as_field, region_masks
from .registry import METHODS, AlignedFields

CORRELATION_COLUMNS = [
    "scene",
    "spp",
    "n_seeds",
    "region",
    "method",
    *RESULT_KEYS,
    "renderer",
    "estimator",
]
"""Columns of the per-scene correlation CSV."""


def correlation_rows(
    sigma_left, sigma_right, aligned: dict, glass, *, finite_right=None, min_pixels: int = 30
) -> list[dict]:
    """Rows region x statistic from an Eq. 2 alignment (paper Sec. 2.3, 3.1).

    For each region :math:`r` of :data:`~stereovar.statistics.regions.REGIONS` and each
    statistic of :data:`~stereovar.statistics.registry.METHODS` (``warp``: Eq. 3,
    ``no_warp``: Eq. 3 without Eq. 2),

    .. math::

        \\rho_{\\text{warp}} = \\mathrm{corr}\\bigl(\\sigma_L^2,\\,
            \\hat\\sigma_{R\\to L}^2\\bigr)\\big|_{\\Omega_r}, \\qquad
        \\rho_{\\text{no-warp}} = \\mathrm{corr}\\bigl(\\sigma_L^2(x, y),\\,
            \\sigma_R^2(x, y)\\bigr)\\big|_{\\Omega_r}.

    :math:`\\Omega` is the warp's valid set (ground-truth ``valid``, :math:`d > 0`,
    correspondence inside the right image) further restricted to pixels whose left value is
    finite and whose warped right value is built only from finite right pixels. Every
    statistic uses the same :math:`\\Omega_r`; the unaligned right field is NaN where a
    render was non-finite, so ``no_warp`` also drops those (rare) pixels.

    Parameters
    ----------
    sigma_left, sigma_right : array_like or xarray.DataArray, shape (H, W)
        :math:`\\sigma_L^2`, :math:`\\sigma_R^2` (Eq. 1).
    aligned : dict
        :func:`stereovar.statistics.warp.align_variance` output (or read back from the
        warped store).
    glass : array_like of bool, shape (H, W)
        The left view's glass mask.
    finite_right : array_like of bool, shape (H, W), optional
        The right variance field's ``finite`` flags.
    min_pixels : int, keyword-only
        Fewest pixels for a defined statistic.

    Returns
    -------
    list of dict
        Rows in the order regions x statistics with ``region``, ``method`` and the statistic's
        result (``rho``, ``n_pixels``, ``ci_low``, ``ci_high``, ``p_value``,
        ``log10_p_value``, ``n_nonfinite``, ``reason``). ``n_nonfinite`` adds the region's
        ground-truth-valid pixels excluded because a render was NaN or Inf; a scene without
        glass gives ``"no glass pixels in the scene"`` for every glass row.
    """
    left = as_field(sigma_left).astype(np.float64)
    right = as_field(sigma_right).astype(np.float64)
    glass = as_field(glass).astype(bool)
    masks = region_masks({"glass": glass}, as_field(aligned["omega"]).astype(bool))
    gt_masks = region_masks({"glass": glass}, as_field(aligned["omega_geometry"]).astype(bool))
    usable = as_field(aligned["usable"]).astype(bool)
    fin_right = np.isfinite(right)
    if finite_right is not None:
        fin_right &= as_field(finite_right).astype(bool)
    fields = AlignedFields(
        left=left,
        warped=as_field(aligned["warped"]).astype(np.float64),
        right=np.where(fin_right, right, np.nan),
    )
    has_glass = bool(glass.any())
    rows = []
    for region in REGIONS:
        excluded = int((gt_masks[region] & ~usable).sum())
        for name, method in METHODS.items():
            if region == "glass" and not has_glass:
                result = undefined_result(0, 0, NO_GLASS)
            else:
                result = method.function(fields, masks[region], min_pixels=min_pixels)
                result["n_nonfinite"] += excluded
            rows.append({"region": region, "method": name, **result})
    return rows
