"""How far two independent fields with spatial structure correlate by chance.

Two variance fields that are independent of each other still correlate by chance, and the
more so the larger their structure: a field that is smooth over 50 pixels has far fewer
independent values than pixels. The spatial block bootstrap
(:mod:`stereovar.statistics.bootstrap`) sees dependence within its tiles only, so for fields
whose structure is larger than a tile it makes an interval too narrow under the hypothesis
that the views are independent. :func:`chance_se` computes the standard error of
:math:`\\rho` under that hypothesis from the two fields' own autocovariances over every lag
(Bartlett 1935), so the chance term of a Monte Carlo-specific difference
(:func:`stereovar.calibration.nulls.difference_interval`) follows the structure of the
fields measured: about :math:`1/\\sqrt n` for white noise, more for structured fields.
"""

from __future__ import annotations

import hashlib
import math
from collections import OrderedDict
from typing import NamedTuple

import numpy as np
from scipy import fft

MIN_PAIR_SHARE = 0.75
"""Lags are summed where at least this share of the region's pixels have a partner at that
lag (about a tenth of the image each way): further out each autocovariance rests on fewer
pairs and its noise, squared, biases the sum up. Measured on 320 x 180 fields (100 draws
each, ``tests/test_chance.py``): standard error over the spread of :math:`\\hat\\rho`
0.97-1.03 for independent fields smoothed over 4, 8 and 16 pixels and for a smooth shared
pattern under white noise (:math:`\\rho` 0.27), where a share of 0.25 gave 1.36 on the last."""


PAIRS_CACHE_SIZE = 8
"""Regions whose pair counts are kept (:func:`_pairs`): the calibration measures every
replicate of a scene on the same few pixel sets."""

_PAIRS_CACHE: OrderedDict = OrderedDict()


class _Pairs(NamedTuple):
    """The lags a region's sum runs over: the padded grid, the flat positions of the lags
    :math:`h` used and of :math:`-h`, and :math:`P(h)` there."""

    padded: tuple[int, int]
    used: np.ndarray
    negated: np.ndarray
    count: np.ndarray


def _pairs(index: np.ndarray, shape: tuple[int, int]) -> _Pairs:
    """:math:`P(h)` of a region and the lags with :math:`P(h) \\ge`
    :data:`MIN_PAIR_SHARE` :math:`n`, kept for the next call on the same pixels (by a
    digest of their positions)."""
    h, w = shape
    key = (h, w, index.size, hashlib.blake2b(np.ascontiguousarray(index, dtype=np.int64)
                                             .tobytes(), digest_size=16).digest())
    hit = _PAIRS_CACHE.get(key)
    if hit is not None:
        _PAIRS_CACHE.move_to_end(key)
        return hit
    padded = (fft.next_fast_len(2 * h - 1, real=True), fft.next_fast_len(2 * w - 1, real=True))
    mask = np.zeros(h * w)
    mask[index] = 1.0
    fm = fft.rfft2(mask.reshape(h, w), s=padded)
    pairs = fft.irfft2(fm * np.conj(fm), s=padded)
    # pair counts are integers up to rounding
    rows, cols = np.nonzero(pairs >= max(MIN_PAIR_SHARE * index.size, 1.0) - 0.5)
    used = rows * padded[1] + cols
    negated = ((-rows) % padded[0]) * padded[1] + (-cols) % padded[1]  # the lag -h
    hit = _Pairs(padded, used, negated, np.rint(pairs.reshape(-1)[used]))
    _PAIRS_CACHE[key] = hit
    while len(_PAIRS_CACHE) > PAIRS_CACHE_SIZE:
        _PAIRS_CACHE.popitem(last=False)
    return hit


def chance_se(a, b, index, shape) -> float:
    """Standard error of Pearson's :math:`\\rho` of two stationary fields with spatial
    structure (Bartlett's formula over every lag).

    .. math::

        \\operatorname{Var}\\hat\\rho \\approx \\sum_h \\frac{P(h)}{n^2}\\Bigl[
            \\rho_{aa}\\rho_{bb} + \\rho_{ab}\\bar\\rho_{ab}
            + \\rho^2\\bigl(\\rho_{ab}^2 + \\tfrac12\\rho_{aa}^2 + \\tfrac12\\rho_{bb}^2\\bigr)
            - 2\\rho\\bigl(\\rho_{aa}\\rho_{ab} + \\bar\\rho_{ab}\\rho_{bb}\\bigr)\\Bigr](h)

    with :math:`\\rho_{aa}(h)`, :math:`\\rho_{bb}(h)` the fields' autocorrelations and
    :math:`\\rho_{ab}(h)`, :math:`\\bar\\rho_{ab}(h) = \\rho_{ab}(-h)` their
    cross-correlation at lag :math:`h` over the region :math:`\\Omega`, each estimated from
    the :math:`P(h) = \\#\\{x : x, x+h \\in \\Omega\\}` pairs at that lag, and the sum
    over the lags with :math:`P(h) \\ge` :data:`MIN_PAIR_SHARE` :math:`n` (Bartlett 1946;
    Box and Jenkins, Eq. 11.1.7, in two dimensions). For independent fields it is
    :math:`\\sum_h P(h)\\,\\rho_{aa}(h)\\rho_{bb}(h)/n^2`; for white fields
    :math:`(1 - \\rho^2)^2/n`, the variance Fisher's interval assumes. Not in the paper: the
    chance term of a correlation's difference from its matched null (Eq. 3, paper Sec. 2.3,
    against a null, ``DESIGN.md``, Calibration).

    Parameters
    ----------
    a, b : array_like, shape (n,)
        The two fields' values at the region's pixels.
    index : array_like of int, shape (n,)
        Each value's flat (row-major) position in an image of ``shape``.
    shape : tuple of int
        (H, W).

    Returns
    -------
    float
        NaN for fewer than 3 pixels or a constant field.

    Examples
    --------
    White noise has no structure beyond its pixel: the standard error is
    :math:`1/\\sqrt n` (here :math:`n = 4096`, :math:`1/64`):

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a, b = rng.standard_normal((2, 64 * 64))
    >>> round(chance_se(a, b, np.arange(a.size), (64, 64)) * 64, 1)
    1.0

    A 4 x 4 moving average of white noise (periodic) has the autocorrelation
    :math:`C(h) = (1 - |h_x|/4)(1 - |h_y|/4)` for :math:`|h_x|, |h_y| < 4`, so
    :math:`\\sum_h C(h)^2 = (1 + 2\\,(9 + 4 + 1)/16)^2 = 2.75^2` and the standard error is
    2.75 times that of white noise:

    >>> from scipy.ndimage import uniform_filter
    >>> a, b = (uniform_filter(x, 4, mode="wrap").ravel()
    ...         for x in rng.standard_normal((2, 128, 128)))
    >>> round(chance_se(a, b, np.arange(a.size), (128, 128)) * 128 / 2.75, 1)
    1.0

    Two white fields correlated 0.8 over :math:`n = 128^2` pixels:
    :math:`(1 - 0.8^2)/128`:

    >>> z, w = rng.standard_normal((2, 128 * 128))
    >>> a, b = z, 0.8 * z + 0.6 * w
    >>> round(chance_se(a, b, np.arange(a.size), (128, 128)) * 128 / 0.36, 1)
    1.0
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    index = np.asarray(index)
    n = a.size
    if n < 3:
        return math.nan
    h, w = (int(s) for s in shape)
    pairs = _pairs(index, (h, w))
    grids = np.zeros((2, h * w))
    grids[0, index] = a - a.mean()
    grids[1, index] = b - b.mean()
    fa, fb = fft.rfft2(grids.reshape(2, h, w), s=pairs.padded)

    def lags(x, y):  # sum over u of x(u + h) y(u), at every lag of the padded grid
        return fft.irfft2(x * np.conj(y), s=pairs.padded).reshape(-1)

    s_aa, s_bb, s_ab = lags(fa, fa), lags(fb, fb), lags(fa, fb)
    var_a, var_b = float(s_aa[0]) / n, float(s_bb[0]) / n
    if not (var_a > 0 and var_b > 0):
        return math.nan
    count = pairs.count
    scale = math.sqrt(var_a * var_b)
    rho = float(s_ab[0]) / n / scale
    r_aa = s_aa[pairs.used] / count / var_a
    r_bb = s_bb[pairs.used] / count / var_b
    r_ab = s_ab[pairs.used] / count / scale
    r_ba = s_ab[pairs.negated] / count / scale
    term = (
        r_aa * r_bb + r_ab * r_ba
        + rho * rho * (r_ab * r_ab + 0.5 * r_aa * r_aa + 0.5 * r_bb * r_bb)
        - 2.0 * rho * (r_aa * r_ab + r_ba * r_bb)
    )
    grid = np.zeros(s_ab.size)  # summed over the whole grid, as the full-grid sum adds
    grid[pairs.used] = count * term
    total = float(np.sum(grid)) / (n * n)
    return math.sqrt(max(total, 0.0))
