"""Pearson correlation over a pixel set (paper Sec. 2.3, Eq. 3, and Sec. 3.1).

:func:`pearson_over_mask` is Eq. 3 over any pixel set with its Fisher-z interval and test; the
registered statistics (:mod:`stereovar.statistics.registry`) call it, and
:mod:`stereovar.statistics.rows` turns them into one scene's rows.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import log_ndtr, ndtri

from .regions import as_field

Z_95 = float(ndtri(0.975))
"""Two-sided 95% quantile of the standard normal, :math:`\\Phi^{-1}(0.975)`."""

NO_GLASS = "no glass pixels in the scene"
CONSTANT = "constant field in region"


RESULT_KEYS = (
    "rho",
    "n_pixels",
    "fisher_low",
    "fisher_high",
    "p_value",
    "log10_p_value",
    "boot_low",
    "boot_high",
    "n_tiles",
    "mean_a",
    "top_share",
    "n_fireflies",
    "n_nonfinite",
    "chance_se",
    "reason",
)
"""What every registered statistic returns (:mod:`stereovar.statistics.registry`):
``fisher_low``/``fisher_high`` assume independent pixels; ``boot_low``/``boot_high`` are the
spatial block bootstrap's (:mod:`stereovar.statistics.bootstrap`); ``chance_se`` is the
standard error of :math:`\\rho` were the two fields independent, for the statistics that
declare it (:func:`stereovar.statistics.chance.chance_se`; NaN otherwise); ``mean_a`` is the mean of
the statistic's left field over the pixels used (for ``warp``, Table 2's mean
:math:`\\sigma_L^2`)."""


def undefined_result(n_pixels: int, n_nonfinite: int, reason: str) -> dict:
    """A statistic's result when it is undefined: NaN numbers and the ``reason``."""
    nan = float("nan")
    return {
        "rho": nan,
        "n_pixels": int(n_pixels),
        "fisher_low": nan,
        "fisher_high": nan,
        "p_value": nan,
        "log10_p_value": nan,
        "boot_low": nan,
        "boot_high": nan,
        "n_tiles": 0,
        "mean_a": nan,
        "top_share": nan,
        "n_fireflies": 0,
        "n_nonfinite": int(n_nonfinite),
        "chance_se": nan,
        "reason": reason,
    }


def log10_two_sided_normal_p(stat: float) -> float:
    """Base-10 log of the two-sided normal p-value :math:`2\\,\\Phi(-|z|)`, without underflow.

    .. math:: \\log_{10} p = \\frac{\\ln 2 + \\ln \\Phi(-|z|)}{\\ln 10}

    with :math:`\\ln\\Phi` from ``scipy.special.log_ndtr``, finite far below 1e-300.
    """
    stat = abs(float(stat))
    if math.isnan(stat):
        return math.nan
    return float((math.log(2.0) + log_ndtr(-stat)) / math.log(10.0))


def fisher_interval(rho: float, n: int) -> dict:
    """Fisher-z interval and two-sided test of :math:`\\rho` over :math:`n` independent pixels.

    .. math::

        z = \\operatorname{artanh} \\rho, \\quad s = \\frac{1}{\\sqrt{n - 3}}, \\qquad
        \\mathrm{CI}_{95} = \\bigl[\\tanh(z - 1.959964\\,s),\\ \\tanh(z + 1.959964\\,s)\\bigr],
        \\qquad p = 2\\,\\Phi\\bigl(-|z|\\sqrt{n - 3}\\bigr)

    (paper Sec. 3.1). Neighbouring pixels are not independent, so this interval is far too
    narrow for variance fields; the block bootstrap's is the honest one.

    Returns
    -------
    dict
        ``fisher_low``, ``fisher_high``, ``p_value``, ``log10_p_value``.

    Examples
    --------
    :math:`\\rho = 0` over :math:`n = 103` pixels: :math:`z = 0`, :math:`s = 0.1`, so the
    interval is :math:`\\pm\\tanh(0.1960)` and :math:`p = 1`:

    >>> out = fisher_interval(0.0, 103)
    >>> round(out["fisher_low"], 4), round(out["fisher_high"], 4), round(out["p_value"], 12)
    (-0.1935, 0.1935, 1.0)
    """
    with np.errstate(divide="ignore"):
        z = float(np.arctanh(rho))
    se = 1.0 / math.sqrt(n - 3)
    log10_p = log10_two_sided_normal_p(z / se)
    return {
        "fisher_low": float(np.tanh(z - Z_95 * se)),
        "fisher_high": float(np.tanh(z + Z_95 * se)),
        "p_value": float(10.0**log10_p),
        "log10_p_value": log10_p,
    }


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
        The :data:`RESULT_KEYS`: ``rho``, ``n_pixels`` (pixels used), the Fisher-z
        ``fisher_low``, ``fisher_high``, ``p_value``,
        ``log10_p_value``, ``n_nonfinite`` (pixels of ``mask`` dropped because ``a`` or ``b``
        is NaN or Inf) and ``reason``: ``""``, or why the correlation is undefined (fewer than
        ``min_pixels`` pixels, or a constant field), in which case the numbers are NaN.

    Examples
    --------
    Over the four pixels of :math:`\\Omega` (the fifth is outside and ignored), the
    deviations from the means are :math:`(-1.5, -0.5, 0.5, 1.5)` for ``a`` and
    :math:`(-1.5, 0.5, -0.5, 1.5)` for ``b``, each with sum of squares 5, so
    :math:`\\rho = (2.25 - 0.25 - 0.25 + 2.25) / 5 = 0.8`:

    >>> import numpy as np
    >>> a = np.array([[1.0, 2.0, 3.0, 4.0, 9.0]])
    >>> b = np.array([[1.0, 3.0, 2.0, 4.0, -9.0]])
    >>> omega = np.array([[True, True, True, True, False]])
    >>> r = pearson_over_mask(a, b, omega, min_pixels=4)
    >>> round(r["rho"], 12), r["n_pixels"], r["reason"]
    (0.8, 4, '')

    With :math:`n = 4` pixels the Fisher-z interval is
    :math:`\\tanh(\\operatorname{artanh} 0.8 \\pm 1.959964)`, wide:

    >>> z = np.arctanh(0.8)
    >>> bool(np.allclose([r["fisher_low"], r["fisher_high"]], np.tanh([z - Z_95, z + Z_95])))
    True

    Pixels where a field is NaN are dropped and counted; a constant field, or too few
    pixels, gives NaN and the reason:

    >>> a[0, 0] = np.nan
    >>> r = pearson_over_mask(a, b, omega, min_pixels=4)
    >>> r["n_pixels"], r["n_nonfinite"], r["reason"]
    (3, 1, 'fewer than 4 valid pixels (n=3)')
    >>> pearson_over_mask(np.ones((1, 5)), b, omega, min_pixels=4)["reason"]
    'constant field in region'
    """
    if min_pixels < 4:
        raise ValueError(
            f"min_pixels must be at least 4 for the Fisher z interval, got {min_pixels}"
        )
    a, b, mask = as_field(a), as_field(b), as_field(mask).astype(bool)
    if not a.shape == b.shape == mask.shape:
        raise ValueError(f"shapes differ: a {a.shape}, b {b.shape}, mask {mask.shape}")
    av = a[mask].astype(np.float64)
    bv = b[mask].astype(np.float64)
    ok = np.isfinite(av) & np.isfinite(bv)
    n_nonfinite = int(ok.size - ok.sum())
    av, bv = av[ok], bv[ok]
    n = int(av.size)
    if n < min_pixels:
        return undefined_result(n, n_nonfinite, f"fewer than {min_pixels} valid pixels (n={n})")
    if av.min() == av.max() or bv.min() == bv.max():
        return undefined_result(n, n_nonfinite, CONSTANT)
    da = av - av.mean()
    db = bv - bv.mean()
    da /= np.abs(da).max()  # Pearson is scale-invariant; this keeps the sums from overflowing
    db /= np.abs(db).max()
    sxx, syy, sxy = (np.einsum("i,i->", x, y) for x, y in ((da, da), (db, db), (da, db)))
    if not (sxx > 0 and syy > 0):
        return undefined_result(n, n_nonfinite, CONSTANT)
    rho = float(np.clip(sxy / math.sqrt(sxx * syy), -1.0, 1.0))
    return {
        **undefined_result(n, n_nonfinite, ""),
        "rho": rho,
        **fisher_interval(rho, n),
    }
