"""The photometric check that settles an audit's disparity convention (paper Eq. 2).

A surface looks nearly the same from both cameras, so the right view's seed mean warped into
the left with the right disparity sign reproduces the left seed mean up to noise,
interpolation and view-dependent shading; with the opposite sign it does not. The audit
warps with the declared convention and with the opposite one and stops when the opposite
one matches clearly better (:func:`sign_check`), before any statistic is computed.

Noise in the seed means (few seeds, low SPP) raises both errors alike. Beside the ratio of
the two median errors the check counts, pixel by pixel, at which share of the pixels the
declared sign matches better, with a 95% tile-bootstrap interval (:attr:`SignCheck.wins`),
and reports it with an inconclusive check. The share does not settle the sign: a disparity
that is no disparity at all (another channel read as depth, say) still gives shares well
off one half on textured images (measured: 0.66 [0.60, 0.73] on a synthetic frame with
random disparities of 20-40 px), as noisy renders with the right disparity do.

The check can only tell the signs apart where the right image differs between the two
matches: where it is flat (black, saturated, or made flat by 8-bit quantisation of a dark
render) both warps give the same value and both errors are the same. A check whose declared
sign is not settled says so, with the reason (:attr:`SignCheck.reason`). A declared sign that
wins with a median error above :data:`HIGH_ERROR` is flagged (:attr:`SignCheck.high_error`):
a depth map read as disparity can win against the opposite sign with a poor match.

A disparity off by a pixel or two (:math:`d + 2`, or :math:`d` replaced by its mean) still
wins clearly, with a median error under :data:`HIGH_ERROR`: the sign check cannot see it;
the offset check (:mod:`stereovar.audit.offset`) can.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..statistics.bootstrap import draw_counts, percentile_interval, tile_labels
from ..statistics.warp import WarpPlan

CLEARLY_BETTER = 0.5
"""The opposite sign wins when its error is below this fraction of the declared one's."""

HIGH_ERROR = 0.15
"""A declared sign whose median error is above this matches poorly even when it wins: the
disparity may not be this frame's (a depth map, another frame, a wrong scale), or the seed
means are very noisy; the import flags it."""

MIN_PIXELS = 100
"""Fewer compared pixels than this leave the check inconclusive."""

SAME = 1e-6
"""The two warps agree at a pixel when they differ by at most this fraction of the left
luminance (floored at this value, as in :func:`median_relative_error`)."""

FLAT = 0.5
"""When the two warps agree at this fraction of the pixels compared under both signs or
more, an inconclusive check is put down to a flat image."""

TILE = 16
"""Side of the bootstrap tiles of the paired comparison (px)."""

REPS = 1000
"""Bootstrap replicates of the paired comparison (seeded: the check is deterministic)."""


def paired_wins(error, opposite_error, pixels, shape, *, tile=TILE, reps=REPS) -> tuple:
    r"""Share of the pixels at which the declared sign matches better, with a 95% interval.

    .. math::

        w = \frac{\#\{x : e(x) < e'(x)\}}{\#\{x : e(x) \ne e'(x)\}}

    with :math:`e, e'` the absolute luminance errors of the declared and the opposite warp
    at the pixels compared under both. Ties (flat pixels) are left out. The interval is
    the percentile interval of a spatial block bootstrap over ``tile`` x ``tile`` tiles
    (neighbouring pixels share a surface and its noise), seeded.

    Returns
    -------
    tuple of float
        :math:`w` and its interval; NaN without any untied pixel.

    Examples
    --------
    >>> import numpy as np
    >>> e = np.array([0.1, 0.1, 0.3, 0.2]); e_opp = np.array([0.2, 0.3, 0.1, 0.2])
    >>> paired_wins(e, e_opp, np.arange(4), (2, 2))[0]  # 2 of the 3 untied pixels
    0.6666666666666666
    """
    error, opposite_error = np.asarray(error), np.asarray(opposite_error)
    decided = error != opposite_error
    if not decided.any():
        return math.nan, math.nan, math.nan
    labels = tile_labels(shape, min(tile, *shape)).reshape(-1)[np.asarray(pixels)[decided]]
    _, labels = np.unique(labels, return_inverse=True)
    won = (error < opposite_error)[decided]
    wins, counts = np.bincount(labels, weights=won), np.bincount(labels).astype(np.float64)
    share = float(wins.sum() / counts.sum())
    if len(counts) < 2:
        return share, math.nan, math.nan
    draws = draw_counts(len(counts), reps, 0)
    low, high = percentile_interval(draws @ wins / (draws @ counts))
    return share, float(low), float(high)


def median_relative_error(left, warped, mask) -> float:
    r"""Median relative luminance error of a warped right image against the left one.

    .. math::

        e = \operatorname{median}_{x \in M}
            \frac{|\bar I_{R\to L}(x) - \bar I_L(x)|}{\max(\bar I_L(x), 10^{-6})}

    with :math:`\bar I` the channel mean and :math:`M` the compared pixels; NaN when
    :math:`M` is empty. ``left`` and ``warped`` are ``(..., C)`` arrays (images, or pixels
    by channel) and ``mask`` selects along their leading dims.
    """
    lum_l = np.asarray(left, dtype=np.float64).mean(axis=-1)[mask]
    lum_w = np.asarray(warped, dtype=np.float64).mean(axis=-1)[mask]
    if lum_l.size == 0:
        return math.nan
    return float(np.median(np.abs(lum_w - lum_l) / np.maximum(lum_l, 1e-6)))


@dataclass(frozen=True)
class SignCheck:
    """Photometric errors of the declared sign and of the opposite one."""

    declared: int
    error: float
    opposite_error: float
    n_pixels: int
    opposite_n_pixels: int
    same_fraction: float = math.nan
    """Fraction of the pixels compared under both signs at which the two warps agree
    (:data:`SAME`); NaN when there is none."""
    wins: tuple = (math.nan, math.nan, math.nan)
    """Share of the untied pixels at which the declared sign matches better, with its 95%
    tile-bootstrap interval (:func:`paired_wins`)."""

    @property
    def opposite_wins(self) -> bool:
        """Whether the opposite sign matches clearly better (:data:`CLEARLY_BETTER`)."""
        if self.opposite_n_pixels < MIN_PIXELS or not math.isfinite(self.opposite_error):
            return False
        if self.n_pixels < MIN_PIXELS or not math.isfinite(self.error):
            return True
        return self.opposite_error < CLEARLY_BETTER * self.error

    @property
    def conclusive(self) -> bool:
        """Whether one sign matches clearly better than the other (:data:`CLEARLY_BETTER`)."""
        if self.opposite_wins:
            return True
        return (
            self.n_pixels >= MIN_PIXELS
            and math.isfinite(self.error)
            and not self.error >= CLEARLY_BETTER * self.opposite_error
        )

    @property
    def reason(self) -> str:
        """Why the check is inconclusive (empty when it is not)."""
        if self.conclusive:
            return ""
        if self.n_pixels < MIN_PIXELS:
            return f"only {self.n_pixels} pixels can be compared ({MIN_PIXELS} needed)"
        if self.same_fraction >= FLAT:
            return (
                f"the two signs' warps agree at {100 * self.same_fraction:.1f}% of the "
                f"{self.n_pixels} compared pixels (the renders are flat there: black, "
                "saturated or flattened by quantisation), so neither sign can match better"
            )
        share, low, high = self.wins
        if math.isfinite(low):
            return (
                "neither sign matches clearly better (the declared one is closer at "
                f"{100 * share:.1f}% [{100 * low:.1f}, {100 * high:.1f}] of the pixels)"
            )
        return "neither sign matches clearly better"

    @property
    def high_error(self) -> bool:
        """Whether the declared sign's median error is above :data:`HIGH_ERROR`."""
        return math.isfinite(self.error) and self.error > HIGH_ERROR

    def attrs(self) -> dict:
        """The check as store attributes."""
        return {
            "sign_check_error": self.error,
            "sign_check_opposite_error": self.opposite_error,
            "sign_check_pixels": self.n_pixels,
            "sign_check_declared_closer": self.wins[0],
        }


def sign_check(mean_left, mean_right, disparity, *, sign: int, valid=None) -> SignCheck:
    """Warp the right seed mean into the left with ``sign`` and with ``-sign`` and compare
    each with the left seed mean (:func:`median_relative_error` over each warp's valid set).

    Parameters
    ----------
    mean_left, mean_right : array_like (H, W, 3)
        The views' seed means.
    disparity : array_like (H, W)
        Left-view disparity magnitude in px.
    sign : {1, -1}, keyword-only
        The declared convention's sign.
    valid : array_like of bool (H, W), optional
        Pixels to compare (e.g. valid and not glass).

    Returns
    -------
    SignCheck
        Both errors and pixel counts, the fraction of the pixels compared under both
        signs at which the two warps agree (:data:`SAME`), and the share of the others at
        which the declared sign matches better (:func:`paired_wins`).
    """
    # Eq. 2 is linear, so the channel mean of the warp is the warp of the channel mean: warp
    # the right luminance only, at the valid pixels only.
    lum_left = np.asarray(mean_left, dtype=np.float64).mean(axis=-1).reshape(-1)
    lum_right = np.asarray(mean_right, dtype=np.float64).mean(axis=-1)
    results, compared = [], []
    for s in (sign, -sign):
        plan = WarpPlan(disparity, sign=s, valid=valid)
        left, warped = lum_left[plan.index], plan.sample(lum_right)
        mask = np.isfinite(left) & np.isfinite(warped)
        error = median_relative_error(left[:, None], warped[:, None], mask)
        results.append((error, int(mask.sum())))
        compared.append((plan.index[mask], left[mask], warped[mask]))
    (err, n), (err_opp, n_opp) = results
    (pixels, left, warped), (pixels_opp, _, warped_opp) = compared
    _, at, at_opp = np.intersect1d(pixels, pixels_opp, assume_unique=True, return_indices=True)
    floor = SAME * np.maximum(left[at], SAME)
    same = np.abs(warped[at] - warped_opp[at_opp]) <= floor
    same_fraction = float(same.mean()) if same.size else math.nan
    wins = paired_wins(
        np.abs(warped[at] - left[at]),
        np.where(same, np.abs(warped[at] - left[at]), np.abs(warped_opp[at_opp] - left[at])),
        pixels[at],
        np.shape(disparity),
    )
    return SignCheck(int(sign), err, err_opp, n, n_opp, same_fraction, wins)
