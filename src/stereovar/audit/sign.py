"""The photometric check that settles an audit's disparity convention (paper Eq. 2).

A surface looks nearly the same from both cameras, so the right view's seed mean warped into
the left with the right disparity sign reproduces the left seed mean up to noise,
interpolation and view-dependent shading; with the opposite sign it does not. The audit
warps with the declared convention and with the opposite one and stops when the opposite
one matches clearly better (:func:`sign_check`), before any statistic is computed.

The check can only tell the signs apart where the right image differs between the two
matches: where it is flat (black, saturated, or made flat by 8-bit quantisation of a dark
render) both warps give the same value and both errors are the same. A check whose declared
sign is not clearly better says so, with the reason (:attr:`SignCheck.reason`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..statistics.warp import WarpPlan

CLEARLY_BETTER = 0.5
"""The opposite sign wins when its error is below this fraction of the declared one's."""

MIN_PIXELS = 100
"""Fewer compared pixels than this leave the check inconclusive."""

SAME = 1e-6
"""The two warps agree at a pixel when they differ by at most this fraction of the left
luminance (floored at this value, as in :func:`median_relative_error`)."""

FLAT = 0.5
"""When the two warps agree at this fraction of the pixels compared under both signs or
more, an inconclusive check is put down to a flat image."""


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
        """Whether one sign matches clearly better than the other."""
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
        return "neither sign matches clearly better"

    def attrs(self) -> dict:
        """The check as store attributes."""
        return {
            "sign_check_error": self.error,
            "sign_check_opposite_error": self.opposite_error,
            "sign_check_pixels": self.n_pixels,
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
        Both errors and pixel counts, and the fraction of the pixels compared under both
        signs at which the two warps agree (:data:`SAME`).
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
    return SignCheck(int(sign), err, err_opp, n, n_opp, same_fraction)
