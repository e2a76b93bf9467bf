"""Streamed stereo cost-volume scans and their matching metrics (paper Sec. 3.4, Table 3).

:func:`scan_cost_volume` runs the windowed sum of absolute differences over integer
disparities, slice by slice with separable box filtering over cache-sized row strips, and keeps
only per-pixel running state: the winner-take-all disparity, the GT margin and the counts
behind the accuracy and its chance level (:func:`scan_hit_rate`). :func:`disparity_slices`
streams the cost slices themselves. The full-volume reference (the whole :math:`(D+1, H, W)`
volume) lives with the tests, in ``tests/reference/costvolume.py``.

Disparities are the integers :math:`d \\in \\{0, \\dots, D\\}`; left pixel :math:`x`
corresponds to :math:`x + s\\,d` with :math:`s = +1` for the paper's
:math:`x_R = x_L + d` convention and :math:`s = -1` for the conventional rig. A pair
:math:`(x, d)` is *scored* only when every pixel the cost reads lies inside the image; the
volumes hold NaN elsewhere and come with a boolean ``scored`` mask of the same shape.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import NamedTuple

import numpy as np

NO_PIXELS = "no scoreable pixel in region"

_SHIFTED_ADD_MAX = 11
"""Largest window summed by shifted adds rather than running sums (speed crossover)."""


def _check_sign(sign) -> int:
    if sign not in (1, -1):
        raise ValueError(f"sign must be +1 or -1, got {sign}")
    return int(sign)


def _check_max_disparity(max_disparity) -> int:
    if isinstance(max_disparity, bool) or int(max_disparity) != max_disparity:
        raise ValueError(f"max_disparity must be an integer, got {max_disparity!r}")
    if max_disparity < 0:
        raise ValueError(f"max_disparity must be >= 0, got {max_disparity}")
    return int(max_disparity)


def _check_window(window) -> int:
    if isinstance(window, bool) or int(window) != window or window < 1 or window % 2 == 0:
        raise ValueError(f"window must be an odd integer >= 1, got {window!r}")
    return int(window)


def _pair(left, right) -> tuple[np.ndarray, np.ndarray]:
    left = np.asarray(left)
    right = np.asarray(right)
    if left.ndim != 2 or left.shape != right.shape:
        raise ValueError(
            f"expected two 2-D fields of equal shape (H, W), got {left.shape} and {right.shape}"
        )
    return left, right


def _scored_columns(width: int, d: int, sign: int, radius: int) -> tuple[int, int]:
    """Inclusive column range ``[lo, hi]`` of pixels scored at disparity ``d`` (empty if lo > hi).

    Both :math:`x + u` and :math:`x + s\\,d + u` must lie in ``[0, width - 1]`` for every
    offset :math:`|u| \\le r`.
    """
    lo = max(radius, radius - sign * d)
    hi = min(width - 1 - radius, width - 1 - radius - sign * d)
    return lo, hi


def _box_sum_1d(a: np.ndarray, window: int, axis: int, dtype=np.float64) -> np.ndarray:
    """Sums of ``window`` consecutive entries along ``axis`` ("valid" part only), in ``dtype``.

    Small windows (up to ``_SHIFTED_ADD_MAX``) add ``window`` shifted views, which is exact
    in summation order and measured ~2.7x faster than running sums for a 5x5 window. Larger
    windows use running (integral-image) sums, ``S[k] = c[k + w] - c[k]`` with ``c`` the
    cumulative sum prefixed by 0, whose cost per entry does not grow with the window.
    """
    if window == 1:
        return a
    n = a.shape[axis]
    if window <= _SHIFTED_ADD_MAX:

        def view(k):
            index = [slice(None)] * a.ndim
            index[axis] = slice(k, k + n - window + 1)
            return a[tuple(index)]

        out = np.array(view(0), dtype=dtype)
        for k in range(1, window):
            out += view(k)
        return out
    shape = list(a.shape)
    shape[axis] = n + 1
    c = np.empty(shape, dtype=np.float64)  # running sums always in float64
    head = [slice(None)] * a.ndim
    head[axis] = slice(0, 1)
    c[tuple(head)] = 0.0
    body = [slice(None)] * a.ndim
    body[axis] = slice(1, None)
    np.cumsum(a, axis=axis, out=c[tuple(body)])
    hi = [slice(None)] * a.ndim
    hi[axis] = slice(window, None)
    lo = [slice(None)] * a.ndim
    lo[axis] = slice(0, n + 1 - window)
    return np.subtract(c[tuple(hi)], c[tuple(lo)]).astype(dtype, copy=False)


def disparity_slices(
    left,
    right,
    *,
    max_disparity: int,
    window: int = 5,
    sign: int = 1,
    dtype=np.float64,
    disparities=None,
) -> Iterator[tuple[int, np.ndarray, tuple[slice, slice]]]:
    """Stream the SAD cost volume one disparity at a time, holding only the scored block.

    .. math::

        C(x, d) = \\sum_{u \\in W} \\bigl|L(x + u) - R(x + s\\,d + u)\\bigr|

    (Sec. 3.4). For each :math:`d = 0, \\dots, D` this yields the costs of the pixels scored
    at :math:`d` only: those whose window lies inside the image both at :math:`x` and at
    :math:`x + s\\,d`. They form a rectangle (rows :math:`r \\dots H-1-r`, a column range that
    depends on :math:`d`, :math:`r` the window radius). One slice is the absolute
    differences over the overlap followed by separable box sums along y and x (shifted adds
    for windows up to 11, running sums above, so :math:`O(HW)` per slice for any window),
    all accumulated in float64.

    Parameters
    ----------
    left, right : array_like, shape (H, W)
        Real-valued fields (images, residuals, variances).
    max_disparity : int, keyword-only
        :math:`D \\ge 0`; disparities :math:`0, \\dots, D` are searched.
    window : int, keyword-only
        Side of the square window :math:`W` centred on the pixel; odd and :math:`\\ge 1`.
    sign : {1, -1}, keyword-only
        :math:`s` above.
    dtype : {numpy.float64, numpy.float32}, keyword-only
        Arithmetic precision of the differences and window sums. float32 halves memory
        traffic; a window sum of :math:`|W|` terms then carries a relative error below
        :math:`|W| \\cdot 6 \\times 10^{-8}`.
    disparities : iterable of int, keyword-only, optional
        The subset of :math:`0, \\dots, D` to yield (all when omitted).

    Yields
    ------
    d : int
        The disparity.
    block : numpy.ndarray of ``dtype``
        :math:`C(\\cdot, d)` over the scored rectangle (possibly of zero size).
    where : tuple of slice
        ``(rows, cols)`` of that rectangle in the (H, W) image, so
        ``cost[d][where] = block`` and ``scored[d][where] = True``.

    Raises
    ------
    ValueError
        For an even or non-positive window, a negative or non-integer ``max_disparity``, a
        ``sign`` other than :math:`\\pm 1`, or fields that are not 2-D of equal shape.
    """
    left, right = _pair(left, right)
    max_disparity = _check_max_disparity(max_disparity)
    window = _check_window(window)
    sign = _check_sign(sign)
    dtype = np.dtype(dtype)
    if dtype not in (np.float32, np.float64):
        raise ValueError(f"dtype must be float32 or float64, got {dtype}")
    height, width = left.shape
    radius = window // 2
    rows = slice(radius, max(radius, height - radius))
    for d in range(max_disparity + 1) if disparities is None else disparities:
        lo, hi = _scored_columns(width, d, sign, radius)
        if hi < lo or height < window:
            yield d, np.empty((0, 0), dtype=dtype), (slice(0, 0), slice(0, 0))
            continue
        a, b = lo - radius, hi + radius + 1
        diff = np.subtract(left[:, a:b], right[:, a + sign * d : b + sign * d], dtype=dtype)
        np.abs(diff, out=diff)
        block = _box_sum_1d(_box_sum_1d(diff, window, 1, dtype), window, 0, dtype)
        yield d, block, (rows, slice(lo, hi + 1))


_STRIP_BYTES = 640 * 1024
"""Target bytes of one row strip of one input: small enough to stay in L2 across the
passes of a disparity slice (measured ~1.7x faster than whole-image passes at 1280x720)."""


def _compute_dtype(left, right, window, dtype) -> np.dtype:
    """Arithmetic type of a scan: ``dtype`` for floats; exact integers for integer images.

    Integer inputs are summed in int16 when :math:`|W| \\cdot \\max|L - R|` fits, else in
    int32 (else float64), so the costs of integer images are exact and ties are real ties.
    """
    if dtype is not None:
        dtype = np.dtype(dtype)
        if dtype not in (np.float32, np.float64):
            raise ValueError(f"dtype must be float32, float64 or None, got {dtype}")
        return dtype
    if left.dtype.kind in "iub" and right.dtype.kind in "iub":
        lo = min(int(left.min(initial=0)), int(right.min(initial=0)))
        hi = max(int(left.max(initial=0)), int(right.max(initial=0)))
        largest = window * window * (hi - lo)
        fits_int32 = np.iinfo(np.int32).min <= lo and hi <= np.iinfo(np.int32).max
        for candidate in (np.int16, np.int32):
            if fits_int32 and largest <= np.iinfo(candidate).max:
                return np.dtype(candidate)
    return np.dtype(np.float64)


def _strip_slices(left, right, rows, *, max_disparity, window, sign, dtype):
    """Yield ``(d, block, cols)``: :math:`C(\\cdot, d)` for the output ``rows`` (a slice of
    rows whose window is inside the image) over the scored column range ``cols``."""
    radius = window // 2
    width = left.shape[1]
    top, bottom = rows.start - radius, rows.stop + radius
    strip_l, strip_r = left[top:bottom], right[top:bottom]
    for d in range(max_disparity + 1):
        lo, hi = _scored_columns(width, d, sign, radius)
        if hi < lo:
            continue
        a, b = lo - radius, hi + radius + 1
        diff = np.subtract(strip_l[:, a:b], strip_r[:, a + sign * d : b + sign * d], dtype=dtype)
        np.abs(diff, out=diff)
        block = _box_sum_1d(_box_sum_1d(diff, window, 1, dtype), window, 0, dtype)
        yield d, block, slice(lo, hi + 1)


class CostScan(NamedTuple):
    """Per-pixel summary of a cost volume from :func:`scan_cost_volume`, all shape (H, W).

    Attributes
    ----------
    disparity : numpy.ndarray of int32
        :math:`\\hat d(x) = \\arg\\min_d C(x, d)` over scored disparities (ties to the
        smallest :math:`d`); -1 where none is scored.
    cost : numpy.ndarray of float64
        :math:`C(x, \\hat d(x))`; +inf where no disparity is scored.
    margin : numpy.ndarray of float64 or None
        GT margin :math:`m(x)` (None without ``d_gt``).
    n_scored : numpy.ndarray of int32 or None
        Number of scored disparities at :math:`x`.
    n_near : numpy.ndarray of int32 or None
        Number of scored disparities within 1 px of the subpixel :math:`d_{GT}(x)`.
    """

    disparity: np.ndarray
    cost: np.ndarray
    margin: np.ndarray | None = None
    n_scored: np.ndarray | None = None
    n_near: np.ndarray | None = None


def scan_cost_volume(
    left,
    right,
    *,
    max_disparity: int,
    window: int = 5,
    sign: int = 1,
    d_gt=None,
    dtype=np.float64,
    workers: int = 1,
) -> CostScan:
    """Winner-take-all and GT margin of the SAD cost volume without holding the volume.

    .. math::

        \\hat d(x) = \\arg\\min_{d \\text{ scored at } x} C(x, d), \\qquad
        m(x) = \\min_{d \\ne d_{GT}} C(x, d) - C(x, d_{GT}),

    with :math:`C(x, d) = \\sum_{u \\in W} |L(x + u) - R(x + s\\,d + u)|` scored as in
    the SAD cost volume (Sec. 3.4) and :math:`d_{GT} = \\operatorname{rint}` of the
    subpixel ground truth (halves to even). The image is cut into row strips that stay in
    cache; each strip runs through :math:`d = 0, \\dots, D` (separable box sums of the
    absolute differences) while keeping running per-pixel minima, so memory is a few
    (H, W) images whatever :math:`D`. Strips are shared among ``workers`` threads (numpy
    releases the GIL). A non-finite cost (from non-finite inputs) is not scored. The
    results equal the GT margin, winner-take-all accuracy and ``numpy.argmin`` of the full
    volume computed in the same ``dtype`` (``tests/reference/costvolume.py``).

    Parameters
    ----------
    left, right : array_like, shape (H, W)
        Real-valued or integer fields.
    max_disparity, window, sign
        As for the SAD cost volume.
    d_gt : array_like, shape (H, W), keyword-only, optional
        Subpixel ground-truth disparity magnitude; when given, ``margin``, ``n_scored``
        and ``n_near`` are computed too.
    dtype : {numpy.float64, numpy.float32, None}, keyword-only
        Arithmetic of the differences and window sums. None picks exact integer
        arithmetic (int16 or int32) for integer images and float64 otherwise.
    workers : int, keyword-only
        Threads.

    Returns
    -------
    CostScan
    """
    from concurrent.futures import ThreadPoolExecutor

    left, right = _pair(left, right)
    max_disparity = _check_max_disparity(max_disparity)
    window = _check_window(window)
    sign = _check_sign(sign)
    dtype = _compute_dtype(left, right, window, dtype)
    left = left.astype(dtype if dtype.kind == "f" else np.int32, copy=False)
    right = right.astype(left.dtype, copy=False)
    height, width = left.shape
    radius = window // 2
    big = np.inf if dtype.kind == "f" else np.iinfo(dtype).max
    best = np.full((height, width), big, dtype=dtype)
    arg = np.full((height, width), -1, dtype=np.int32)
    with_gt = d_gt is not None
    if with_gt:
        g = gt_field(d_gt, (height, width))
        with np.errstate(invalid="ignore"):
            finite = np.isfinite(g)
            rounded = np.rint(g)
            in_range = finite & (rounded >= 0) & (rounded <= max_disparity)
            d_int = np.where(in_range, rounded, -1).astype(np.int32)
            floor = np.where(finite, np.floor(g), -1).astype(np.int32)
            ceil = np.where(finite, np.ceil(g), -1).astype(np.int32)
        ceil[ceil == floor] = -1  # an integer ground truth has one neighbour within 1 px
        c_gt = np.full((height, width), np.nan)
        other = np.full((height, width), np.inf)
        n_scored = np.zeros((height, width), dtype=np.int32)
        n_near = np.zeros((height, width), dtype=np.int32)
    check_finite = dtype.kind == "f" and not (np.isfinite(left).all() and np.isfinite(right).all())
    strip = max(8, _STRIP_BYTES // max(1, width * dtype.itemsize))
    strips = [
        slice(k, min(k + strip, height - radius)) for k in range(radius, height - radius, strip)
    ]

    def run(rows):
        mask = np.empty((rows.stop - rows.start, width), dtype=bool)
        for d, block, cols in _strip_slices(
            left, right, rows, max_disparity=max_disparity, window=window, sign=sign, dtype=dtype
        ):
            where = (rows, cols)
            m = mask[:, cols]
            np.less(block, best[where], out=m)  # NaN never wins
            np.copyto(best[where], block, where=m)
            np.copyto(arg[where], d, where=m)
            if not with_gt:
                continue
            ok = np.isfinite(block) if check_finite else True
            n_scored[where] += ok
            n_near[where] += ((floor[where] == d) | (ceil[where] == d)) & ok
            np.equal(d_int[where], d, out=m)
            np.copyto(c_gt[where], block, where=m)
            np.logical_not(m, out=m)
            np.fmin(other[where], block, out=other[where], where=m)

    with ThreadPoolExecutor(max_workers=max(1, int(workers))) as pool:
        list(pool.map(run, strips))
    cost = best.astype(np.float64)
    cost[arg < 0] = np.inf
    if not with_gt:
        return CostScan(arg, cost)
    with np.errstate(invalid="ignore"):
        margin = np.where(np.isfinite(c_gt) & np.isfinite(other), other - c_gt, np.nan)
    return CostScan(arg, cost, margin, n_scored, n_near)


def scan_hit_rate(scan: CostScan, d_gt, mask=None) -> dict:
    """Winner-take-all accuracy of a :class:`CostScan` over a region (Sec. 3.4, Table 3).

    .. math::

        \\Pr_x\\bigl[\\,|\\hat d(x) - d_{GT}(x)| < 1\\,\\bigr]

    over the region's scoreable pixels (some scored :math:`d` within 1 px of the subpixel
    ground truth), with the chance level
    :math:`\\frac{1}{n}\\sum_x n_{\\mathrm{near}}(x) / n_{\\mathrm{scored}}(x)`. Equal to
    the full-volume ``wta_accuracy`` of the reference; same returned dict.

    Parameters
    ----------
    scan : CostScan
        From :func:`scan_cost_volume` with the same ``d_gt``.
    d_gt : array_like, shape (H, W)
        Subpixel ground-truth disparity magnitude.
    mask : array_like of bool, shape (H, W), optional
        Region; all pixels if omitted.
    """
    if scan.n_near is None:
        raise ValueError("the scan has no ground-truth counts; pass d_gt to scan_cost_volume")
    g = gt_field(d_gt, scan.disparity.shape)
    region = np.ones(g.shape, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    if region.shape != g.shape:
        raise ValueError(f"mask shape {region.shape} does not match the scan's {g.shape}")
    keep = region & np.isfinite(g) & (scan.n_near > 0)
    hits = np.abs(scan.disparity[keep] - g[keep]) < 1.0
    return rate_result(hits, scan.n_near[keep] / scan.n_scored[keep])


def wta_disparity(
    left,
    right,
    *,
    max_disparity: int,
    window: int = 5,
    sign: int = 1,
    dtype=np.float32,
    workers: int = 2,
):
    """Winner-take-all disparity of the SAD cost volume, streamed (Sec. 3.4).

    .. math:: \\hat d(x) = \\arg\\min_{d \\text{ scored at } x} C(x, d)

    :func:`scan_cost_volume` without the ground truth; float32 by default here, for speed
    (``None`` gives exact integer arithmetic for integer images). Ties go to the smallest
    :math:`d`, as ``numpy.argmin`` over the full volume.

    Returns
    -------
    disparity : numpy.ndarray of int64, shape (H, W)
        :math:`\\hat d`; -1 where no disparity is scored.
    cost : numpy.ndarray of float64, shape (H, W)
        The winning cost; +inf where no disparity is scored.
    """
    scan = scan_cost_volume(
        left,
        right,
        max_disparity=max_disparity,
        window=window,
        sign=sign,
        dtype=dtype,
        workers=workers,
    )
    return scan.disparity.astype(np.int64), scan.cost


def gt_field(d_gt, shape) -> np.ndarray:
    d_gt = np.asarray(d_gt, dtype=np.float64)
    if d_gt.shape != shape:
        raise ValueError(f"d_gt shape {d_gt.shape} does not match the volume's {shape}")
    return d_gt


def rate_result(hits: np.ndarray, chance: np.ndarray) -> dict:
    """The accuracy dict of a winner-take-all from per-pixel hits and chance levels."""
    if hits.size == 0:
        nan = float("nan")
        return {"accuracy": nan, "n_pixels": 0, "n_hits": 0, "chance": nan, "reason": NO_PIXELS}
    return {
        "accuracy": float(hits.mean()),
        "n_pixels": int(hits.size),
        "n_hits": int(hits.sum()),
        "chance": float(chance.mean()),
        "reason": "",
    }
