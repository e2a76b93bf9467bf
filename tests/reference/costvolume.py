"""Dense cost volumes: the slow full-volume reference for the streamed scans.

Each function builds the whole :math:`(D + 1, H, W)` volume of paper Sec. 3.4 (memory grows
with :math:`D`); :mod:`stereovar.intervention.scan` computes the same metrics without holding
it. Used only by the tests and the benchmarks.
"""

from __future__ import annotations

import numpy as np

from stereovar.intervention.scan import (
    _check_max_disparity,
    _check_sign,
    _pair,
    _scored_columns,
    disparity_slices,
    gt_field,
    rate_result,
)


def sad_cost_volume(
    left, right, *, max_disparity: int, window: int = 5, sign: int = 1, dtype=np.float64
) -> tuple[np.ndarray, np.ndarray]:
    """Windowed SAD cost volume over integer disparities (Sec. 3.4).

    .. math::

        C(x, d) = \\sum_{u \\in W} \\bigl|L(x + u) - R(x + s\\,d + u)\\bigr|,
        \\qquad d = 0, \\dots, D,

    with :math:`W` the square ``window`` centred on the pixel. :math:`(x, d)` is scored only
    if :math:`x + u` and :math:`x + s\\,d + u` stay inside the image for every
    :math:`u \\in W`; otherwise the cost is NaN. Built by :func:`disparity_slices` (separable
    box sums, a loop over :math:`d` only); use that generator directly to avoid holding
    the full volume.

    Parameters
    ----------
    left, right : array_like, shape (H, W)
        Real-valued fields.
    max_disparity : int, keyword-only
        :math:`D \\ge 0`.
    window : int, keyword-only
        Odd window side :math:`\\ge 1` (default 5, the paper's :math:`5 \\times 5`).
    sign : {1, -1}, keyword-only
        :math:`s`: ``+1`` for :math:`x_R = x_L + d` (paper), ``-1`` for
        :math:`x_R = x_L - d` (conventional, e.g. OpenCV).
    dtype : {numpy.float64, numpy.float32}, keyword-only
        Storage type of ``cost``. The sums are always accumulated in float64; float32 only
        rounds the finished sums (halving the memory of the volume).

    Returns
    -------
    cost : numpy.ndarray, shape (D + 1, H, W)
        :math:`C(x, d)`; NaN where not scored.
    scored : numpy.ndarray of bool, shape (D + 1, H, W)
        Whether :math:`(x, d)` is scored.
    """
    dtype = np.dtype(dtype)
    if dtype not in (np.dtype(np.float64), np.dtype(np.float32)):
        raise ValueError(f"dtype must be float64 or float32, got {dtype}")
    left, right = _pair(left, right)
    max_disparity = _check_max_disparity(max_disparity)
    cost = np.full((max_disparity + 1,) + left.shape, np.nan, dtype=dtype)
    scored = np.zeros(cost.shape, dtype=bool)
    for d, block, where in disparity_slices(
        left, right, max_disparity=max_disparity, window=window, sign=sign
    ):
        cost[d][where] = block
        scored[d][where] = True
    return cost, scored


def residual_cost_volume(
    eps_left, eps_right, *, max_disparity: int, window: int = 5, sign: int = 1, dtype=np.float64
) -> tuple[np.ndarray, np.ndarray]:
    """Residual SAD :math:`C_\\epsilon` on one seed's Monte Carlo residuals (Sec. 3.4).

    .. math::

        C_\\epsilon(x, d) = \\sum_{u \\in W}
            \\bigl|\\epsilon_L(x + u) - \\epsilon_R(x + s\\,d + u)\\bigr|,
        \\qquad \\epsilon^{(n)} = I^{(n)} - \\bar I,

    with :math:`\\bar I` the across-seed mean of the view, which removes the dominant
    clean-image SAD and isolates the MC signal. ``eps_left``/``eps_right`` are the (H, W)
    residuals :math:`\\epsilon_L^{(n)}`, :math:`\\epsilon_R^{(n)}` of one seed :math:`n`; the
    options and return values are those of :func:`sad_cost_volume`.
    """
    return sad_cost_volume(
        eps_left, eps_right, max_disparity=max_disparity, window=window, sign=sign, dtype=dtype
    )


def variance_cost_volume(
    sigma_left,
    sigma_right,
    *,
    max_disparity: int,
    window: int = 5,
    sign: int = 1,
    dtype=np.float64,
) -> tuple[np.ndarray, np.ndarray]:
    """Variance cost :math:`C_\\sigma`, the SAD of the variance fields (Sec. 3.4).

    .. math::

        C_\\sigma(x, d) = \\sum_{u \\in W}
            \\bigl|\\sigma_L^2(x + u) - \\sigma_R^2(x + s\\,d + u)\\bigr|

    ``sigma_left``/``sigma_right`` are the per-pixel variance fields :math:`\\sigma^2` of the
    two views (variances, not standard deviations), shape (H, W); the options and return
    values are those of :func:`sad_cost_volume`.
    """
    return sad_cost_volume(
        sigma_left, sigma_right, max_disparity=max_disparity, window=window, sign=sign, dtype=dtype
    )


def pixel_similarity_volume(
    sigma_left, sigma_right, *, max_disparity: int, sign: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    """Pixel-level variance similarity, whose argmax gives the peak hit rate (Sec. 3.4).

    .. math::

        S(x, d) = -\\bigl|\\sigma_L^2(x) - \\sigma_R^2(x + s\\,d)\\bigr|

    No window: :math:`(x, d)` is scored when :math:`x + s\\,d` lies in ``[0, W - 1]``.

    Parameters
    ----------
    sigma_left, sigma_right : array_like, shape (H, W)
        Variance fields :math:`\\sigma^2` of the two views.
    max_disparity : int, keyword-only
        :math:`D \\ge 0`.
    sign : {1, -1}, keyword-only
        :math:`s`.

    Returns
    -------
    similarity : numpy.ndarray of float64, shape (D + 1, H, W)
        :math:`S(x, d)`; NaN where not scored.
    scored : numpy.ndarray of bool, shape (D + 1, H, W)
    """
    left, right = _pair(sigma_left, sigma_right)
    max_disparity = _check_max_disparity(max_disparity)
    sign = _check_sign(sign)
    width = left.shape[1]
    sim = np.full((max_disparity + 1,) + left.shape, np.nan, dtype=np.float64)
    scored = np.zeros(sim.shape, dtype=bool)
    for d in range(max_disparity + 1):
        lo, hi = _scored_columns(width, d, sign, 0)
        if hi < lo:
            continue
        cols = slice(lo, hi + 1)
        shifted = slice(lo + sign * d, hi + 1 + sign * d)
        sim[d][:, cols] = -np.abs(np.subtract(left[:, cols], right[:, shifted], dtype=np.float64))
        scored[d][:, cols] = True
    return sim, scored


def _volume(values, scored) -> tuple[np.ndarray, np.ndarray]:
    values = np.asarray(values)
    scored = np.asarray(scored, dtype=bool)
    if values.ndim != 3 or scored.shape != values.shape:
        raise ValueError(
            f"expected a (D + 1, H, W) volume and a scored mask of the same shape, got "
            f"{values.shape} and {scored.shape}"
        )
    # A non-finite value (e.g. from NaN inputs) is never a candidate.
    return values, scored & np.isfinite(values)


def gt_margin(cost, scored, d_gt) -> np.ndarray:
    """GT margin of a cost volume (Sec. 3.4); higher is more salient.

    .. math::

        m(x) = \\min_{d \\ne d_{\\mathrm{GT}}} C(x, d) - C(x, d_{\\mathrm{GT}})

    with the minimum over scored :math:`d` and :math:`d_{\\mathrm{GT}}(x)` the integer
    nearest the subpixel ground truth, ``numpy.rint`` (halves go to the even integer:
    2.5 -> 2, 3.5 -> 4).

    Parameters
    ----------
    cost : numpy.ndarray, shape (D + 1, H, W)
        :math:`C(x, d)`, e.g. from :func:`sad_cost_volume`.
    scored : numpy.ndarray of bool, shape (D + 1, H, W)
        Scored pairs; a non-finite cost also counts as not scored.
    d_gt : array_like, shape (H, W)
        Subpixel ground-truth disparity magnitude (same sign convention as the volume).

    Returns
    -------
    margin : numpy.ndarray of float64, shape (H, W)
        :math:`m(x)`; NaN where :math:`d_{\\mathrm{GT}}` is non-finite, outside
        :math:`[0, D]` or not scored, or where no other disparity is scored.
    """
    cost, scored = _volume(cost, scored)
    n_disp = cost.shape[0]
    d_gt = gt_field(d_gt, cost.shape[1:])
    with np.errstate(invalid="ignore"):
        d_int = np.rint(d_gt)
        ok = np.isfinite(d_int) & (d_int >= 0) & (d_int <= n_disp - 1)
    idx = np.where(ok, d_int, 0).astype(np.intp)[None]
    c_gt = np.take_along_axis(cost, idx, axis=0)[0].astype(np.float64)
    ok &= np.take_along_axis(scored, idx, axis=0)[0]
    others = np.where(scored, cost, np.inf).astype(np.float64, copy=False)
    np.put_along_axis(others, idx, np.inf, axis=0)
    best_other = others.min(axis=0)
    ok &= np.isfinite(best_other)
    return np.where(ok, best_other - np.where(ok, c_gt, 0.0), np.nan)


def _hit_rate(values, scored, d_gt, mask, *, maximise: bool) -> dict:
    values, scored = _volume(values, scored)
    n_disp = values.shape[0]
    d_gt = gt_field(d_gt, values.shape[1:])
    region = np.ones(values.shape[1:], dtype=bool) if mask is None else np.asarray(mask, bool)
    if region.shape != values.shape[1:]:
        raise ValueError(f"mask shape {region.shape} does not match the volume's")
    n_scored = scored.sum(axis=0)
    eligible = region & (n_scored > 0) & np.isfinite(d_gt)
    v = values[:, eligible].astype(np.float64)
    s = scored[:, eligible]
    g = d_gt[eligible]
    d = np.arange(n_disp, dtype=np.float64)[:, None]
    near = (np.abs(d - g[None]) < 1.0) & s
    # A pixel is scoreable only if some disparity within 1 px of its ground truth is scored.
    keep = near.any(axis=0)
    if not keep.any():
        return rate_result(np.empty(0, bool), np.empty(0))
    v, s, g, near = v[:, keep], s[:, keep], g[keep], near[:, keep]
    v = np.where(s, -v if maximise else v, np.inf)
    best = np.argmin(v, axis=0)
    return rate_result(np.abs(best - g) < 1.0, near.sum(axis=0) / s.sum(axis=0))


def wta_accuracy(cost, scored, d_gt, mask=None) -> dict:
    """Winner-take-all accuracy of a cost volume (Sec. 3.4, Table 3).

    .. math::

        \\Pr_x\\bigl[\\,|\\hat d(x) - d_{\\mathrm{GT}}(x)| < 1\\,\\bigr], \\qquad
        \\hat d(x) = \\arg\\min_{d \\text{ scored}} C(x, d)

    over the region's *scoreable* pixels (a finite ``d_gt`` and at least one scored
    disparity within 1 px of it, so a hit is possible), against the *subpixel* ground
    truth (so up to two integer disparities count as a hit). Ties go to the smallest
    :math:`d` (``numpy.argmin``).

    Parameters
    ----------
    cost, scored : numpy.ndarray, shape (D + 1, H, W)
        Cost volume and scored mask; a non-finite cost counts as not scored.
    d_gt : array_like, shape (H, W)
        Subpixel ground-truth disparity magnitude.
    mask : array_like of bool, shape (H, W), optional
        Region (e.g. glass / non-glass within the valid set); all pixels if omitted.

    Returns
    -------
    dict
        ``accuracy`` (hit fraction), ``n_pixels`` (scoreable region pixels), ``n_hits``,
        ``chance`` and ``reason`` (``""``, or why accuracy is NaN: no scoreable pixel).
        ``chance`` is the accuracy of a uniformly random choice among each pixel's scored
        disparities, averaged over the pixels:
        :math:`\\frac{1}{n}\\sum_x |\\{d \\text{ scored}: |d - d_{\\mathrm{GT}}(x)| < 1\\}|
        \\,/\\, |\\{d \\text{ scored}\\}|` (about :math:`1/(D + 1)` to :math:`2/(D + 1)`).
    """
    return _hit_rate(cost, scored, d_gt, mask, maximise=False)


def peak_hit_rate(similarity, scored, d_gt, mask=None) -> dict:
    """Variance-similarity peak hit rate (Sec. 3.4, Table 3).

    .. math::

        \\Pr_x\\bigl[\\,|\\hat d(x) - d_{\\mathrm{GT}}(x)| < 1\\,\\bigr], \\qquad
        \\hat d(x) = \\arg\\max_{d \\text{ scored}}
            -\\bigl|\\sigma_L^2(x) - \\sigma_R^2(x + s\\,d)\\bigr|

    i.e. :func:`wta_accuracy` with argmax of a similarity volume such as
    :func:`pixel_similarity_volume` (ties to the smallest :math:`d`). Same parameters and
    returned dict as :func:`wta_accuracy`.
    """
    return _hit_rate(similarity, scored, d_gt, mask, maximise=True)
