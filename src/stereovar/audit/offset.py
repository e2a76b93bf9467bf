"""The photometric check that finds a disparity off by a constant, or by an amount that varies.

The sign check (:mod:`stereovar.audit.sign`) tells the two conventions apart, not a disparity
that is off by a pixel or two: declared as :math:`d + 2` px, or replaced by its mean, the
disparity of a synthetic frame (:func:`stereovar.audit.synthetic.synthetic_frame`) still
beats the opposite sign by far, with median errors of 6.0% and 4.8% under the sign check's
15% flag (2.0% with the right disparity). This check warps the right seed mean into the
left with the declared disparity shifted by whole pixels, :math:`d + \\delta` for
:math:`\\delta = -4, \\dots, 4` (:func:`shifted_errors`), and compares the median errors
(:func:`offset_check`). A correct disparity is a local minimum of the warp's error; one off
by more than half a pixel is not: the error falls towards the true shift. The check fires
(:attr:`OffsetCheck.fires`) when

* over the whole frame, a shifted disparity's median error is below :data:`GLOBAL_LOWER`
  times the declared one's, or
* tiles of :data:`TILE` px holding :data:`SHARE` of the compared pixels or more match
  clearly better (:data:`CLEARLY_LOWER`) at :math:`d + 1` or :math:`d - 1`: a disparity
  replaced by its mean is off by different amounts in different rows, so no one shift
  matches the whole frame better, but most tiles' errors fall towards their own.

Only a frame or tile whose errors change with the shift (the largest median error at least
:data:`TEXTURE` times the smallest) counts: in a flat one (black, saturated, textureless or
drowned in noise) every shift matches alike, and its medians only differ by chance.

The shifts are whole pixels so that every shifted warp interpolates with the declared
disparity's weights: a half-pixel shift of an integer disparity averages two noisy right
pixels, which lowers the error by denoising alone (measured on smooth textures with 5-10%
noise: a median error at :math:`d + 0.5` of 0.84-0.91 times the one at the right integer
disparity), so it cannot be compared with the declared warp. The offset is estimated below a
pixel by a parabola through the frame's errors around the best whole shift (:func:`vertex`).

The check cannot see an offset under about half a pixel (the declared warp and the one a
pixel towards the truth are then about as far from it; on block textures, up to 0.7 px),
nor one in flat or very noisy renders: where the seed means' noise changes the error as
much as a pixel's shift of the texture does, the errors hardly depend on the shift. Its
thresholds were set on synthetic frames with known disparities (``bench/offset_check.py``:
no false alarm in 1330 frames with the right disparity).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..statistics.warp import WarpPlan

MAX_SHIFT = 4
"""The largest whole-pixel shift of the declared disparity compared (px)."""

GLOBAL_LOWER = 0.85
"""The check fires when a shifted disparity's median error over the frame is below this
fraction of the declared disparity's, in a frame that tells the shifts apart
(:data:`TEXTURE`); measured with the right disparity on synthetic frames: 1.01 or more."""

CLEARLY_LOWER = 0.8
"""A tile matches better at :math:`d \\pm 1` when its median error there is below this
fraction of its median error at :math:`d`."""

SHARE = 0.25
"""The check fires when the tiles that match better at :math:`d \\pm 1` hold this share
of the compared pixels or more, among :data:`MIN_TILES` or more tiles that tell the shifts
apart; measured with the right disparity on synthetic frames: 0.13 or less."""

TEXTURE = 1.5
"""A frame or tile tells the shifts apart when its largest median error over the shifts is
at least this many times its smallest; flat ones are left out."""

TILE = 16
"""Side of the tiles compared on their own (px)."""

MIN_TILE_PIXELS = 128
"""A tile with fewer compared pixels than this is left out of the tile comparison."""

MIN_TILES = 4
"""Fewer tiles that tell the shifts apart (:data:`TEXTURE`) than this leave the tile
comparison silent."""

MIN_PIXELS = 100
"""Fewer compared pixels than this leave the check silent."""

VARIES = 1
"""The tiles that match better at :math:`d \\pm 1` read as one offset when their best whole
shifts (10th to 90th percentile over their pixels) span at most this many pixels, and as an
offset that varies across the frame otherwise."""


def shifted_errors(
    mean_left, mean_right, disparity, *, sign: int, valid=None, max_shift: int = MAX_SHIFT
) -> tuple:
    r"""Per-pixel relative luminance errors of the warp with the disparity shifted by whole
    pixels.

    .. math::

        e_\delta(x) = \frac{|\bar I_R(x + s\,(d(x) + \delta)) - \bar I_L(x)|}
            {\max(\bar I_L(x), 10^{-6})}, \qquad \delta = -m, \dots, m

    with :math:`\bar I` the channel mean of a seed mean, :math:`s` the declared sign and
    :math:`m` = ``max_shift``. The warp with :math:`d + \delta` is the declared warp (one
    :class:`~stereovar.statistics.warp.WarpPlan`) of the right image moved by
    :math:`s\,\delta` whole pixels, so every shift interpolates with the declared
    disparity's weights. Pixels are kept where every shift's match lies inside the right
    image.

    Parameters
    ----------
    mean_left, mean_right : array_like (H, W, 3)
        The views' seed means.
    disparity : array_like (H, W)
        Left-view disparity magnitude in px.
    sign : {1, -1}, keyword-only
        The declared convention's sign.
    valid : array_like of bool (H, W), optional
        Pixels to compare.
    max_shift : int, keyword-only
        :math:`m`.

    Returns
    -------
    shifts : numpy.ndarray of int, (2m + 1,)
        :math:`\delta`, from :math:`-m` to :math:`m`.
    errors : numpy.ndarray, (2m + 1, n)
        :math:`e_\delta` at the kept pixels.
    pixels : numpy.ndarray of int, (n,)
        The kept pixels' flat indices.

    Examples
    --------
    A right row that is the left one moved 2 px left (:math:`x_R = x_L - 2`), declared as a
    disparity of 3 px: the shift :math:`\delta = -1` reproduces the left row exactly.

    >>> import numpy as np
    >>> left = np.tile(np.array([1.0, 2.0, 4.0, 3.0, 1.0, 5.0, 2.0, 4.0])[None, :, None], 3)
    >>> right = np.zeros_like(left); right[:, :-2] = left[:, 2:]
    >>> shifts, errors, pixels = shifted_errors(
    ...     left, right, np.full((1, 8), 3.0), sign=-1, max_shift=1)
    >>> shifts.tolist(), pixels.tolist(), errors[0].tolist()
    ([-1, 0, 1], [4, 5, 6, 7], [0.0, 0.0, 0.0, 0.0])
    """
    lum_left = np.asarray(mean_left, dtype=np.float64).mean(axis=-1).reshape(-1)
    lum_right = np.asarray(mean_right, dtype=np.float64).mean(axis=-1)
    d = np.asarray(disparity, dtype=np.float64)
    width = d.shape[1]
    # only pixels whose match stays inside the right image under every shift: the taps of
    # every shifted warp are then pixels of the image, and moving it by np.roll is exact
    with np.errstate(invalid="ignore"):
        match = np.arange(width)[None, :] + sign * d
        inside = (match >= max_shift) & (match <= width - 1 - max_shift)
    if valid is not None:
        inside &= np.asarray(valid, dtype=bool)
    plan = WarpPlan(d, sign=sign, valid=inside)
    shifts = np.arange(-max_shift, max_shift + 1)
    left = lum_left[plan.index]
    scale = np.maximum(left, 1e-6)
    errors = np.empty((len(shifts), left.size))
    for row, k in zip(errors, shifts, strict=True):  # one shift at a time: 8 bytes a pixel
        row[:] = plan.sample(np.roll(lum_right, -sign * int(k), axis=1))
        row -= left
        np.abs(row, out=row)
        row /= scale
    keep = np.isfinite(errors).all(axis=0)
    if keep.all():
        return shifts, errors, plan.index
    return shifts, errors[:, keep], plan.index[keep]


def tile_medians(errors, pixels, shape, tile: int = TILE) -> tuple:
    r"""Median of each row of ``errors`` over each ``tile`` x ``tile`` tile's pixels.

    .. math::

        E_{\delta, t} = \operatorname{median}_{x \in t} e_\delta(x)

    Returns
    -------
    medians : numpy.ndarray, (len(errors), n_tiles)
        Over the tiles that hold a compared pixel, in the order of their labels.
    counts : numpy.ndarray of int, (n_tiles,)
        Compared pixels per tile.

    Examples
    --------
    >>> import numpy as np
    >>> errors = np.array([[1.0, 5.0, 2.0, 7.0, 9.0]])
    >>> medians, counts = tile_medians(errors, np.array([0, 1, 2, 3, 4]), (1, 5), tile=1)
    >>> medians.tolist(), counts.tolist()
    ([[1.0, 5.0, 2.0, 7.0, 9.0]], [1, 1, 1, 1, 1])
    >>> medians, counts = tile_medians(errors, np.array([0, 1, 2, 3, 4]), (1, 5), tile=5)
    >>> medians.tolist(), counts.tolist()
    ([[5.0]], [5])
    """
    errors = np.atleast_2d(np.asarray(errors, dtype=np.float64))
    ys, xs = np.divmod(np.asarray(pixels), shape[1])
    _, labels = np.unique((ys // tile) * -(-shape[1] // tile) + xs // tile, return_inverse=True)
    counts = np.bincount(labels)
    # each tile's errors in a row of its own, padded with +inf, sorted: the median is read
    # at the tile's count
    place = (labels, (ys % tile) * tile + xs % tile)
    rows = np.arange(len(counts))
    dense = np.empty((len(counts), tile * tile))
    out = np.empty((len(errors), len(counts)))
    for k, values in enumerate(errors):
        dense.fill(np.inf)
        dense[place] = values
        dense.sort(axis=1)
        out[k] = 0.5 * (dense[rows, (counts - 1) // 2] + dense[rows, counts // 2])
    return out, counts


def vertex(shifts, curve) -> float:
    r"""The shift that minimises an error curve sampled at whole shifts, below a pixel.

    .. math::

        \hat\delta = \delta^* + \frac{E(\delta^* - 1) - E(\delta^* + 1)}
            {2\,(E(\delta^* - 1) - 2E(\delta^*) + E(\delta^* + 1))}

    the vertex of the parabola through the smallest sample :math:`E(\delta^*)` and its two
    neighbours, kept within half a pixel of :math:`\delta^*`; :math:`\delta^*` itself at
    the end of the range.

    Examples
    --------
    >>> vertex([-2, -1, 0, 1, 2], [5.0, 2.0, 1.0, 2.0, 5.0])
    0.0
    >>> vertex([-2, -1, 0, 1, 2], [6.0, 3.0, 1.0, 1.0, 3.0])
    0.5
    """
    curve = np.asarray(curve, dtype=np.float64)
    best = int(np.argmin(curve))
    if best in (0, len(curve) - 1):
        return float(shifts[best])
    before, at, after = curve[best - 1 : best + 2]
    bend = before - 2 * at + after
    step = 0.0 if bend <= 0 else float(np.clip((before - after) / (2 * bend), -0.5, 0.5))
    return float(shifts[best]) + step


@dataclass(frozen=True)
class OffsetCheck:
    """Median warp errors of the declared disparity shifted by whole pixels, over the whole
    frame and per tile."""

    shifts: tuple
    """:math:`\\delta`, whole pixels from ``-MAX_SHIFT`` to ``MAX_SHIFT``."""
    errors: tuple
    """The frame's median relative error at each shift (NaN without compared pixels)."""
    n_pixels: int
    """Pixels compared under every shift."""
    share: float = math.nan
    """Share of the compared pixels (in tiles with :data:`MIN_TILE_PIXELS` or more) whose tile
    tells the shifts apart (:data:`TEXTURE`) and matches better at :math:`d + 1` or
    :math:`d - 1` (:data:`CLEARLY_LOWER`); NaN without such tiles."""
    n_tiles: int = 0
    """Tiles that tell the shifts apart (:data:`TEXTURE`)."""
    tile_shifts: tuple = (math.nan, math.nan)
    """10th and 90th percentile, over the pixels of the tiles that match better at
    :math:`d \\pm 1`, of each tile's best whole shift; NaN without such a tile."""

    def error_at(self, shift: int) -> float:
        """The frame's median error at :math:`d + \\delta`."""
        return self.errors[list(self.shifts).index(shift)]

    @property
    def best_shift(self) -> float:
        """The shift that minimises the frame's median error, below a pixel (:func:`vertex`);
        NaN without compared pixels."""
        if not np.isfinite(self.errors).all():
            return math.nan
        return vertex(self.shifts, self.errors)

    @property
    def offset(self) -> float:
        """The declared disparity minus the best-matching one, :math:`-\\hat\\delta` (px)."""
        return 0.0 - self.best_shift

    @property
    def frame_fires(self) -> bool:
        """Whether a shifted disparity matches the whole frame better (:data:`GLOBAL_LOWER`),
        in a frame that tells the shifts apart (:data:`TEXTURE`)."""
        errors = np.asarray(self.errors)
        if self.n_pixels < MIN_PIXELS or not np.isfinite(errors).all():
            return False
        others = np.delete(errors, list(self.shifts).index(0))
        return bool(
            errors.max() >= TEXTURE * errors.min()
            and others.min() < GLOBAL_LOWER * self.error_at(0)
        )

    @property
    def tiles_fire(self) -> bool:
        """Whether tiles holding :data:`SHARE` of the compared pixels or more match better at
        :math:`d \\pm 1`, among :data:`MIN_TILES` or more that tell the shifts apart."""
        return (
            self.n_pixels >= MIN_PIXELS
            and self.n_tiles >= MIN_TILES
            and math.isfinite(self.share)
            and self.share >= SHARE
        )

    @property
    def fires(self) -> bool:
        """Whether the declared disparity seems off: :attr:`frame_fires` or
        :attr:`tiles_fire`."""
        return self.frame_fires or self.tiles_fire

    @property
    def best_whole_shift(self) -> int:
        """The whole shift with the frame's smallest median error (0 without compared
        pixels)."""
        errors = np.asarray(self.errors)
        if not np.isfinite(errors).all():
            return 0
        return int(self.shifts[int(np.argmin(errors))])

    @property
    def varies(self) -> bool:
        """Whether the check fires on a disparity off by an amount that varies across the
        frame rather than by one offset: the frame's error is smallest at :math:`d`, or the
        tiles' best shifts span more than :data:`VARIES` px while no shift matches the whole
        frame clearly better (:attr:`frame_fires`)."""
        low, high = self.tile_shifts
        spread = math.isfinite(low) and high - low > VARIES
        return self.fires and (
            self.best_whole_shift == 0 or (spread and not self.frame_fires)
        )

    def attrs(self) -> dict:
        """The check as store attributes."""
        return {
            f"offset_check_{k}": v
            for k, v in self.facts().items()
            if k in ("error", "plus_error", "minus_error", "offset", "share")
        }

    def facts(self) -> dict:
        """The check as JSON for the frame's import record: the frame's median errors at
        :math:`d`, :math:`d + 1` and :math:`d - 1`, the estimated offset, the tiles' share,
        and whether it fires."""
        return {
            "error": self.error_at(0),
            "plus_error": self.error_at(1),
            "minus_error": self.error_at(-1),
            "offset": self.offset,
            "share": self.share,
            "tile_shifts": list(self.tile_shifts),
            "varies": self.varies,
            "fires": self.fires,
        }

    def finding(self) -> str:
        """What the check found, as the import's warning says it (the frame's name and the
        fix are the importer's)."""
        best = self.best_whole_shift
        tiles = (
            f"{TILE}x{TILE} px tiles holding {100 * self.share:.0f}% of the compared pixels "
            "match clearly better at d+1 or d-1"
            if math.isfinite(self.share)
            else "no tile tells the shifts apart"
        )
        if self.varies:
            low, high = self.tile_shifts
            return (
                "the disparity seems off by an amount that varies across the frame: "
                f"{tiles}, their best shifts ranging from d{low:+.0f} to d{high:+.0f} (the "
                f"whole frame's median error is {100 * self.error_at(0):.1f}% at d, "
                f"{100 * self.error_at(1):.1f}% at d+1, {100 * self.error_at(-1):.1f}% at d-1)"
            )
        near = int(np.sign(best))
        if not self.error_at(near) < self.error_at(0):
            near = best
        return (
            f"the disparity seems offset by about {self.offset:+.1f} px: the warp matches "
            f"better at d{near:+d} (error {100 * self.error_at(near):.1f}%) than at d "
            f"({100 * self.error_at(0):.1f}%), best at d{best:+d} "
            f"({100 * self.error_at(best):.1f}%); {tiles}"
        )


def offset_check(
    mean_left, mean_right, disparity, *, sign: int, valid=None, max_shift: int = MAX_SHIFT,
    tile: int = TILE,
) -> OffsetCheck:
    r"""Compare the warp's error at the declared disparity with its error at whole-pixel
    shifts of it, over the frame and per tile.

    .. math::

        E(\delta) = \operatorname{median}_x e_\delta(x), \qquad
        \text{share} = \frac{\sum_t n_t\, [\min(E_t(-1), E_t(+1)) < c\,E_t(0)]\,
            [\max_\delta E_t(\delta) \ge \tau \min_\delta E_t(\delta)]}{\sum_t n_t}

    with :math:`e_\delta` of :func:`shifted_errors`, :math:`E_t` its medians over the tiles
    with :math:`n_t \ge` :data:`MIN_TILE_PIXELS` compared pixels (:func:`tile_medians`),
    :math:`c` = :data:`CLEARLY_LOWER` and :math:`\tau` = :data:`TEXTURE`. Whether it fires:
    :attr:`OffsetCheck.fires`.

    Parameters
    ----------
    mean_left, mean_right : array_like (H, W, 3)
        The views' seed means.
    disparity : array_like (H, W)
        Left-view disparity magnitude in px.
    sign : {1, -1}, keyword-only
        The declared convention's sign.
    valid : array_like of bool (H, W), optional
        Pixels to compare (e.g. valid, not glass, not occluded).
    max_shift, tile : int, keyword-only
        The largest shift and the tiles' side (px).

    Returns
    -------
    OffsetCheck

    Examples
    --------
    A frame of striped rows whose right view is the left one moved by 3 px
    (:math:`x_R = x_L - 3`), declared with a disparity of 5 px: the warp matches best 2 px
    lower, over the frame and in every tile; declared with 3 px, nothing fires.

    >>> import numpy as np
    >>> phase = np.random.default_rng(0).uniform(0, 6, (32, 1))
    >>> left = (0.6 + 0.3 * np.sin(np.arange(64) / 2 + phase))[..., None].repeat(3, axis=-1)
    >>> right = np.roll(left, -3, axis=1)
    >>> check = offset_check(left, right, np.full((32, 64), 5.0), sign=-1)
    >>> check.fires, round(check.offset, 1), check.share
    (True, 2.0, 1.0)
    >>> found, numbers = check.finding().split(": ", 1)
    >>> found
    'the disparity seems offset by about +2.0 px'
    >>> numbers.split(";")[0]
    'the warp matches better at d-1 (error 18.7%) than at d (34.5%), best at d-2 (0.0%)'
    >>> offset_check(left, right, np.full((32, 64), 3.0), sign=-1).fires
    False
    """
    shifts, errors, pixels = shifted_errors(
        mean_left, mean_right, disparity, sign=sign, valid=valid, max_shift=max_shift
    )
    shifts = tuple(int(k) for k in shifts)
    if pixels.size == 0:
        return OffsetCheck(shifts, (math.nan,) * len(shifts), 0)
    curve = tuple(float(v) for v in np.median(errors, axis=1))
    medians, counts = tile_medians(errors, pixels, np.shape(disparity), tile)
    used = counts >= MIN_TILE_PIXELS
    if not used.any():
        return OffsetCheck(shifts, curve, int(pixels.size))
    medians, counts = medians[:, used], counts[used]
    tells = medians.max(axis=0) >= TEXTURE * medians.min(axis=0)
    at = shifts.index
    near = np.minimum(medians[at(-1)], medians[at(1)])
    better = tells & (near < CLEARLY_LOWER * medians[at(0)])
    share = float(counts[better].sum() / counts.sum())
    spread = (math.nan, math.nan)
    if better.any():
        best = np.asarray(shifts)[np.argmin(medians[:, better], axis=0)]
        low, high = np.percentile(np.repeat(best, counts[better]), [10, 90])
        spread = (float(low), float(high))
    return OffsetCheck(shifts, curve, int(pixels.size), share, int(tells.sum()), spread)
