"""Null alignments: Eq. 2 with a wrong disparity or a flipped right view (paper Sec. 2.2).

A correlation that survives a wrong alignment is not evidence of a correspondence cue: these
give the level that an unrelated alignment of the same fields reaches.
"""

from __future__ import annotations

import numpy as np

from ..statistics.warp import warp_right_to_left


def shifted_warp(right, disparity, shift: float, *, sign: int, valid=None) -> np.ndarray:
    """Eq. 2 with the disparity off by ``shift`` pixels.

    .. math:: \\hat f^{(k)}_{R\\to L}(x, y) = f_R\\bigl(x + s\\,(d(x, y) + k),\\, y\\bigr)

    Returns
    -------
    numpy.ndarray, float64 (H, W)
        NaN where the shifted correspondence leaves the image or the disparity is not valid.
    """
    d = np.asarray(disparity, dtype=np.float64) + float(shift)
    warped, omega = warp_right_to_left(
        np.asarray(right, dtype=np.float64), d, sign=sign, valid=valid
    )
    return np.where(omega, warped, np.nan)


def flipped_warp(right, disparity, *, sign: int, valid=None) -> np.ndarray:
    """Eq. 2 applied to the right field flipped upside down.

    .. math::

        \\hat f^{\\updownarrow}_{R\\to L}(x, y) = f_R\\bigl(x + s\\,d(x, y),\\, H - 1 - y\\bigr)

    Returns
    -------
    numpy.ndarray, float64 (H, W)
        NaN outside the warp's valid set.
    """
    flipped = np.asarray(right, dtype=np.float64)[::-1]
    warped, omega = warp_right_to_left(flipped, disparity, sign=sign, valid=valid)
    return np.where(omega, warped, np.nan)
