"""Where the cue is strongest: the audit's frames ranked, and the tiles of the top frames.

Data-audit tools show their most extreme examples beside their summary numbers; the verdict
page does the same, each example beside the control that says whether it is extreme:

1. **frames**, ranked by the intensity-controlled :math:`\\rho` minus its matched null
   (:func:`frame_ranking`: the per-frame :math:`\\Delta_s` of
   :func:`stereovar.statistics.matched_null.matched_difference`), or by the
   intensity-controlled :math:`\\rho` alone when the calibration's nulls are missing;
2. **tiles** of a frame (:data:`TILE` pixels square), ranked by the local
   intensity-controlled correlation (:func:`tile_correlation` of
   :func:`residual_fields`),

   .. math::

       \\rho_t = \\operatorname{corr}\\bigl(e_L, e_{R\\to L}\\bigr)\\big|_{\\Omega \\cap t},
       \\qquad e_V = \\ln\\sigma_V^2 - \\hat g_V(\\ln\\mu_V),

   with :math:`\\hat g_V` the spline of the frame's ``partial`` statistic
   (:func:`stereovar.controls.partial.partial_pair` over the frame's :math:`\\Omega`, Eq. 2
   and Eq. 3 of paper Sec. 2.2-2.3 on what intensity does not explain);
3. **the control of each ranked tile** (:func:`rank_tiles`): the tile of the same rank when
   :math:`e_{R\\to L}` is moved by a far circular offset (the ``misaligned`` null of
   :mod:`stereovar.calibration.synthesis`), over :data:`NULL_OFFSETS` offsets. Step-down
   from the top: the tile ranked :math:`k`, with :math:`m` tiles above it standing out,
   *stands out* when they all do and its :math:`\\rho_t` is above the null's
   :math:`(k - m)`-th largest tile in enough offsets for a Monte Carlo test at 5%,

   .. math:: p = \\frac{1 + \\#\\{j : \\rho^{(j)}_{(k - m)} \\ge \\rho_t\\}}{1 + J} \\le 0.05,

   with :math:`J` offsets (with :data:`NULL_OFFSETS` = 24: above every one). The top of a
   frame with no aligned structure reaches the null's top, so a ranked tile is compared with
   what ranking alone produces (a step-down max-statistic test over the frame's tiles; the
   calibration on 192 x 256 synthetic frames measured 3 of 80 null frames with a tile
   standing out, and 20 of 20 frames with three planted tiles ranking and passing them,
   ``tests/test_audit_strongest.py``). Its 95%
   interval is
   :math:`\\rho_t \\pm 1.96\\, s_0`, with :math:`s_0` the standard deviation of the null's
   tile correlations (their chance spread under this frame's spatial structure; Fisher's
   interval on the tile's pixel count would be too narrow, as neighbouring pixels are not
   independent).

A tile's :math:`\\rho_t` is a local, intensity-controlled correlation; it is not called Monte
Carlo-specific: only the frame's difference from its matched null is.
"""

from __future__ import annotations

import math

import numpy as np

TILE = 32
"""Side of a tile, in pixels."""

NULL_OFFSETS = 24
"""Far circular offsets of the right residual field that make a frame's tile null."""

TOP_FRAMES = 3
"""Frames whose tiles the page shows."""

TOP_TILES = 5
"""Tiles per frame the page shows."""

MIN_SHARE = 0.25
"""A tile is ranked when at least this share of its pixels (and at least ``min_pixels``) are
in :math:`\\Omega` with finite fields in both views."""

Z = 1.959963984540054
"""The normal 97.5% quantile."""

TILE_COLUMNS = [
    "frame",
    "rank",
    "x0",
    "x1",
    "y0",
    "y1",
    "n_pixels",
    "rho",
    "low",
    "high",
    "null",
    "null_high",
    "stands_out",
]
"""Columns of :func:`rank_tiles`' rows: the tile's pixel box (``x1``, ``y1`` exclusive), its
valid pixels, :math:`\\rho_t` with its 95% interval, the null's median at the same rank and
its critical value (what :math:`\\rho_t` must exceed for the Monte Carlo test at 5%), and
whether :math:`\\rho_t` is above it."""

ALPHA = 0.05
"""The level of a tile's Monte Carlo test against the null at its rank."""


def critical_value(nulls, alpha: float = ALPHA) -> np.ndarray:
    """Per rank, the value a tile must exceed for the Monte Carlo test at level ``alpha``:
    the :math:`\\lceil (1 - \\alpha)(J + 1)\\rceil`-th smallest of the :math:`J` null values
    at that rank (the largest when :math:`(J + 1)\\alpha < 2`), so that
    :math:`p = (1 + \\#\\{\\rho^{(j)} \\ge \\rho_t\\}) / (1 + J) \\le \\alpha`.

    Examples
    --------
    >>> import numpy as np
    >>> nulls = np.arange(24.0)[:, None] * [1.0, -1.0] - [0.0, 1.0]  # 24 offsets, 2 ranks
    >>> critical_value(nulls).tolist()
    [23.0, -1.0]
    >>> critical_value(np.arange(99.0)[:, None]).tolist()  # 95th of 99: p = 5 / 100
    [94.0]
    """
    nulls = np.asarray(nulls, dtype=np.float64)
    out = np.full(nulls.shape[1:], np.nan)
    for r in range(nulls.shape[1]):
        v = np.sort(nulls[:, r][np.isfinite(nulls[:, r])])
        if v.size:
            at = min(int(math.ceil((1 - alpha) * (v.size + 1))), v.size)
            out[r] = v[at - 1]
    return out

FRAME_COLUMNS = ["rank", "frame", "value", "low", "high", "partial", "null", "statistic"]
"""Columns of :func:`frame_ranking`: ``value`` [``low``, ``high``] is what the frames are
ranked by (``statistic``: ``difference`` from the matched null, or ``partial``), ``partial``
the frame's intensity-controlled :math:`\\rho` and ``null`` its matched null."""


def _f(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def tile_correlation(a, b, mask, *, tile: int = TILE, min_pixels: int = 30):
    """Pearson's :math:`\\rho` of ``a`` and ``b`` within each ``tile`` x ``tile`` tile.

    .. math::

        \\rho_t = \\frac{\\sum_{i \\in t} (a_i - \\bar a_t)(b_i - \\bar b_t)}
            {\\sqrt{\\sum_{i \\in t} (a_i - \\bar a_t)^2 \\sum_{i \\in t} (b_i - \\bar b_t)^2}}

    over the tile's pixels where ``mask`` holds and both values are finite. Tiles start at
    pixel 0; the last row and column of tiles may be smaller.

    Parameters
    ----------
    a, b : array_like (H, W)
    mask : array_like of bool (H, W)
    tile : int, keyword-only
    min_pixels : int, keyword-only
        Fewer pixels (or :data:`MIN_SHARE` of a full tile): NaN.

    Returns
    -------
    rho, n : numpy.ndarray (ceil(H / tile), ceil(W / tile))
        The tiles' correlations (NaN when undefined) and pixel counts.

    Examples
    --------
    A 4 x 4 image of 2 x 2 tiles; ``b`` follows ``a`` in the left tiles and opposes it in
    the right ones:

    >>> import numpy as np
    >>> a = np.tile([[1.0, 2.0, 1.0, 2.0], [3.0, 5.0, 3.0, 5.0]], (2, 1))
    >>> b = a * np.array([1.0, 1.0, -1.0, -1.0])
    >>> rho, n = tile_correlation(a, b, np.ones((4, 4), bool), tile=2, min_pixels=3)
    >>> rho.round(6).tolist(), n.tolist()
    ([[1.0, -1.0], [1.0, -1.0]], [[4, 4], [4, 4]])
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    ok = np.asarray(mask, dtype=bool) & np.isfinite(a) & np.isfinite(b)
    h, w = a.shape
    ny, nx = -(-h // tile), -(-w // tile)

    def blocks(x):
        out = np.zeros((ny * tile, nx * tile), dtype=x.dtype)
        out[:h, :w] = x
        return out.reshape(ny, tile, nx, tile)

    okb = blocks(ok)
    n = okb.sum(axis=(1, 3))
    safe = np.maximum(n, 1)
    ab, bb = blocks(np.where(ok, a, 0.0)), blocks(np.where(ok, b, 0.0))
    da = (ab - (ab.sum(axis=(1, 3)) / safe)[:, None, :, None]) * okb
    db = (bb - (bb.sum(axis=(1, 3)) / safe)[:, None, :, None]) * okb
    sab = np.einsum("iajb,iajb->ij", da, db)
    saa = np.einsum("iajb,iajb->ij", da, da)
    sbb = np.einsum("iajb,iajb->ij", db, db)
    enough = (n >= max(min_pixels, 2)) & (n >= MIN_SHARE * tile * tile) & (saa > 0) & (sbb > 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        rho = np.where(enough, sab / np.sqrt(saa * sbb), np.nan)
    return np.clip(rho, -1.0, 1.0), n


def residual_fields(sigma_left, warped, omega, mu_left=None, mu_warped=None, covariates=None):
    """The two views' :math:`\\ln\\sigma^2` residuals after intensity, as images.

    .. math:: e_V = \\ln\\sigma_V^2 - \\hat g_V(\\ln\\mu_V)

    over :math:`\\Omega` (:func:`stereovar.controls.partial.partial_pair`, the frame's
    ``partial`` statistic); without the intensities (a variance store without the seed
    mean), :math:`\\ln\\sigma_V^2` minus its mean over :math:`\\Omega`, no intensity
    control.

    Parameters
    ----------
    sigma_left, warped : array_like (H, W)
        :math:`\\sigma_L^2` and :math:`\\hat\\sigma_{R\\to L}^2` (Eq. 1, Eq. 2).
    omega : array_like of bool (H, W)
        The valid set of Eq. 3.
    mu_left, mu_warped : array_like (H, W), optional
        :math:`\\mu_L` and :math:`\\hat\\mu_{R\\to L}`.
    covariates : tuple of numpy.ndarray (H, W), optional
        :func:`stereovar.statistics.fields.control_covariates`: the control then removes
        each view's chromaticity and sensor position too, as the ``partial`` statistic does.

    Returns
    -------
    e_left, e_right, controlled : numpy.ndarray (H, W), numpy.ndarray (H, W), bool
        NaN outside :math:`\\Omega` or where a field is not finite; ``controlled``: whether
        intensity was removed.
    """
    from ..controls.partial import partial_pair
    from ..statistics.robust import log_floor

    a = np.asarray(sigma_left, dtype=np.float64)
    b = np.asarray(warped, dtype=np.float64)
    keep = np.asarray(omega, dtype=bool) & np.isfinite(a) & np.isfinite(b)
    controlled = mu_left is not None and mu_warped is not None
    if controlled:
        mu_a = np.asarray(mu_left, dtype=np.float64)
        mu_b = np.asarray(mu_warped, dtype=np.float64)
        keep &= np.isfinite(mu_a) & np.isfinite(mu_b)
    e_left, e_right = np.full(a.shape, np.nan), np.full(a.shape, np.nan)
    if keep.sum() < 2:
        return e_left, e_right, controlled
    if controlled and covariates:
        fields = [np.asarray(c, dtype=np.float64) for c in covariates]
        for f in fields:
            keep &= np.isfinite(f)
        half = len(fields) // 2
        picked = [f[keep] for f in fields]
        ea, eb = partial_pair(a[keep], b[keep], mu_a[keep], mu_b[keep],
                              covariates=(picked[:half], picked[half:]))
    elif controlled:
        ea, eb = partial_pair(a[keep], b[keep], mu_a[keep], mu_b[keep])
    else:
        ea, eb = log_floor(a[keep])[0], log_floor(b[keep])[0]
        ea, eb = ea - ea.mean(), eb - eb.mean()
    e_left[keep], e_right[keep] = ea, eb
    return e_left, e_right, controlled


def far_offsets(shape, count: int, rng: np.random.Generator) -> list[tuple[int, int]]:
    """``count`` circular offsets :math:`(\\Delta y, \\Delta x)` at least a quarter of the
    image away in x or y (:data:`stereovar.calibration.synthesis.MIN_OFFSET_FRACTION`), as
    :func:`stereovar.calibration.synthesis.misaligned_variance` draws them."""
    from ..calibration.synthesis import MIN_OFFSET_FRACTION

    h, w = shape
    out = []
    while len(out) < count:
        dy, dx = int(rng.integers(0, h)), int(rng.integers(0, w))
        if min(dx, w - dx) >= MIN_OFFSET_FRACTION * w or min(dy, h - dy) >= MIN_OFFSET_FRACTION * h:
            out.append((dy, dx))
    return out


def null_tiles(e_left, e_right, *, tile=TILE, min_pixels=30, offsets=NULL_OFFSETS, seed=0):
    """The tiles' correlations when :math:`e_{R\\to L}` is moved by far circular offsets
    (:func:`far_offsets`): shape ``(offsets, tiles)``, each row sorted from the largest
    correlation down (NaN last)."""
    rng = np.random.default_rng(seed)
    ok = np.isfinite(e_left)
    out = []
    for dy, dx in far_offsets(e_left.shape, offsets, rng):
        moved = np.roll(e_right, (dy, dx), axis=(0, 1))
        rho, _ = tile_correlation(e_left, moved, ok, tile=tile, min_pixels=min_pixels)
        values = rho.ravel()
        out.append(-np.sort(-values))  # descending, NaN last
    return np.array(out)


def rank_tiles(
    e_left,
    e_right,
    *,
    frame: str = "",
    tile: int = TILE,
    top: int = TOP_TILES,
    min_pixels: int = 30,
    offsets: int = NULL_OFFSETS,
    seed: int = 0,
) -> tuple[list[dict], dict]:
    """A frame's tiles ranked by :math:`\\rho_t`, each beside the null at its rank (see the
    module docstring).

    Parameters
    ----------
    e_left, e_right : numpy.ndarray (H, W)
        :func:`residual_fields` (NaN outside :math:`\\Omega`).
    frame : str, keyword-only
    tile, top, min_pixels, offsets, seed : int, keyword-only
        Tile side, tiles returned, pixels a tile needs, null offsets, the null's seed.

    Returns
    -------
    rows : list of dict
        The ``top`` tiles, :data:`TILE_COLUMNS`.
    frame_summary : dict
        ``rho`` (the tiles' correlation map), ``n_tiles`` (ranked tiles), ``n_stand_out``
        (tiles above the null at their rank), ``null_sd`` (:math:`s_0`).
    """
    ok = np.isfinite(e_left) & np.isfinite(e_right)
    rho, n = tile_correlation(e_left, e_right, ok, tile=tile, min_pixels=min_pixels)
    nulls = null_tiles(e_left, e_right, tile=tile, min_pixels=min_pixels, offsets=offsets,
                       seed=seed)
    finite_null = nulls[np.isfinite(nulls)]
    sd = float(finite_null.std(ddof=1)) if finite_null.size > 1 else math.nan
    flat = rho.ravel()
    order = [i for i in np.argsort(-np.where(np.isfinite(flat), flat, -np.inf)) if
             np.isfinite(flat[i])]
    with np.errstate(all="ignore"):
        null_mid = np.nanmedian(nulls, axis=0) if nulls.size else np.array([])
        null_top = critical_value(nulls) if nulls.size else np.array([])
    h, w = e_left.shape
    rows, stand_out, stepping = [], 0, True
    for k, i in enumerate(order):
        y, x = divmod(int(i), rho.shape[1])
        value = float(flat[i])
        j = k - stand_out  # the null's rank among the tiles not already standing out
        mid = float(null_mid[j]) if j < null_mid.size else math.nan
        high = float(null_top[j]) if j < null_top.size else math.nan
        out = bool(stepping and math.isfinite(high) and value > high)
        stepping = out
        stand_out += out
        if k >= top:
            continue
        rows.append({
            "frame": frame,
            "rank": k + 1,
            "x0": x * tile,
            "x1": min((x + 1) * tile, w),
            "y0": y * tile,
            "y1": min((y + 1) * tile, h),
            "n_pixels": int(n[y, x]),
            "rho": value,
            "low": max(value - Z * sd, -1.0) if math.isfinite(sd) else math.nan,
            "high": min(value + Z * sd, 1.0) if math.isfinite(sd) else math.nan,
            "null": mid,
            "null_high": high,
            "stands_out": out,
        })
    return rows, {"rho": rho, "n_tiles": len(order), "n_stand_out": stand_out, "null_sd": sd}


def frame_ranking(correlations: list[dict], nulls: list[dict] | None = None) -> list[dict]:
    """The audit's frames ranked by what the verdict rests on (:data:`FRAME_COLUMNS`).

    .. math:: \\Delta_s = \\rho_{\\text{partial}, s} - \\bar\\rho_{0, s}

    with its interval (:func:`stereovar.calibration.nulls.difference_interval`), for
    frames with a matched null (``transform`` ``none``, region ``all``); a frame without one
    is ranked after them by its intensity-controlled :math:`\\rho` (``statistic``
    ``partial``).

    Examples
    --------
    >>> corr = [{"scene": s, "region": "all", "method": "partial", "rho": r,
    ...          "boot_low": r - 0.1, "boot_high": r + 0.1} for s, r in (("a", 0.2), ("b", 0.5))]
    >>> nulls = [{"scene": s, "transform": "none", "region": "all", "method": "partial",
    ...           "null_rho": 0.1, "null_se": 0.0, "chance_sd": 0.0} for s in "ab"]
    >>> [(r["frame"], round(r["value"], 3)) for r in frame_ranking(corr, nulls)]
    [('b', 0.4), ('a', 0.1)]
    >>> [r["statistic"] for r in frame_ranking(corr)]
    ['partial', 'partial']
    """
    from ..calibration.nulls import difference_interval

    table = {
        r["scene"]: r
        for r in nulls or []
        if (r["transform"], r["region"], r["method"]) == ("none", "all", "partial")
    }
    out = []
    for r in correlations:
        if (r["region"], r["method"]) != ("all", "partial"):
            continue
        rho, low, high = _f(r["rho"]), _f(r.get("boot_low")), _f(r.get("boot_high"))
        null = table.get(r["scene"])
        if null is not None:
            diff = difference_interval(rho, low, high, null["null_rho"], null["null_se"],
                                       r.get("chance_se", math.nan))
            if all(math.isfinite(x) for x in diff):
                out.append({"frame": r["scene"], "value": diff[0], "low": diff[1],
                            "high": diff[2], "partial": rho, "null": _f(null["null_rho"]),
                            "statistic": "difference"})
                continue
        out.append({"frame": r["scene"], "value": rho, "low": low, "high": high,
                    "partial": rho, "null": math.nan, "statistic": "partial"})

    def key(r):
        finite = math.isfinite(r["value"])
        return (r["statistic"] != "difference", not finite, -r["value"] if finite else 0.0)

    out.sort(key=key)
    return [{"rank": k + 1, **r} for k, r in enumerate(out)]
