"""The intensity control: cross-view variance structure beyond what intensity explains.

A camera's noise variance is a function of the signal (:mod:`stereovar.controls.sensor`), and
both views see the same scene, so any two signal-dependent noise fields correlate once
aligned. Removing each view's variance-intensity relation leaves the part of the cross-view
structure that such a sensor would not have.

The relation is removed by a flexible conditional mean of :math:`\\ln\\sigma^2` given
:math:`\\ln\\mu` (a cubic regression spline whose resolution the data choose,
:func:`fit_intensity`), not by a fixed low-order curve: whatever the fit misses is a function
of :math:`\\mu`, which both views share once aligned, so a misfit correlates across views and
reads as a cue. The global cubic it replaces left a partial :math:`\\rho` of 0.6 to 0.98 on
``equalise``'s output, whose variance is exactly :math:`(N-1)/N\\,(a\\mu + b)`, and 0.1 to 0.5
on Eq. 1 of a camera's frames at a :math:`\\ln\\mu` spread of 2.5
(``tests/test_intensity_control.py``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.interpolate import BSpline
from scipy.linalg import LinAlgError, solveh_banded

BINS = 4096
"""Equal-width bins of :math:`\\ln\\mu` over a region's range whose moments the fits read
(fewer for a region of under 16 384 pixels: one per 4 pixels, at least 256). Knots sit on bin
edges, so each bin holds one cubic piece and the fit from the moments is the exact
least-squares fit over the pixels; the bins only bound how close two knots can be."""

MAX_INTERVALS = 512
"""The finest resolution tried: knot intervals of the spline."""

MIN_PIXELS_PER_INTERVAL = 16
"""A resolution is tried only with at least this many pixels per knot interval."""

MIN_PIXELS = 5
"""Fewer finite pixels than this give NaN residuals (a cubic has 4 coefficients)."""

MIN_RESIDUAL_VARIANCE = 1e-3
"""Least variance of a view's control residuals (in :math:`\\ln\\sigma^2`) for
:func:`stereovar.controls.partial.partial_pair` to have anything to correlate. Eq. 1 from :math:`N`
independent renders leaves its own estimation noise, :math:`\\psi_1(C(N-1)/2) \\approx 2/(C(N-1))`
(above :math:`10^{-3}` for :math:`C = 3` channels up to :math:`N \\approx 670`); a field the control
explains more closely is a function of the seed mean it reads (``equalise``'s output:
:math:`(N-1)/N\\,(a\\bar\\mu^+ + b)`, residual variance 1e-13 to 2e-5), whose residuals are
round-off and a few pixels off the law, so :math:`\\rho` would be a heavy-tailed remainder whose
bootstrap interval covers 71-84% of replicates (``tests/test_equalise_coverage.py``)."""

PENALTY = 1e-12
"""Weight of the second-difference penalty on the spline coefficients, relative to the mean
diagonal of the normal equations: it only decides coefficients the data leave free (knot
intervals with too few distinct intensities); it moves a fit by a few 1e-9 in
:math:`\\ln\\sigma^2`."""

_NODES = np.cos(np.pi * (2 * np.arange(4) + 1) / 8)
"""Four Chebyshev points in :math:`(-1, 1)` at which a knot interval's cubics are sampled."""

_TO_MONOMIAL = np.linalg.inv(np.vander(_NODES, 4, increasing=True))
"""Values of a cubic at :data:`_NODES` to its coefficients of :math:`s^0, \\ldots, s^3`."""

_BINOMIAL = np.array([[math.comb(k, i) for i in range(7)] for k in range(7)], dtype=np.float64)
"""Binomial coefficients :math:`\\binom{k}{i}`, row :math:`k`."""

_HANKEL = np.add.outer(np.arange(4), np.arange(4))
"""Which moment :math:`\\sum s^{r+c}` fills entry (r, c) of a cubic's normal equations."""


class IntensityFit(NamedTuple):
    """The intensity control of one view over one region (:func:`fit_intensity`).

    Attributes
    ----------
    residuals : numpy.ndarray, shape (n,)
        :math:`e_i = \\ln\\sigma^2_i - \\hat g(\\ln\\mu_i)`; NaN where an input is not
        finite, everywhere when fewer than :data:`MIN_PIXELS` pixels are finite.
    intervals : int
        Knot intervals :math:`K` of the spline used (0 when there was nothing to fit;
        fewer than asked for where quantiles share a bin edge).
    gcv : float
        Its generalised cross-validation score :math:`\\mathrm{GCV}(K)`.
    """

    residuals: np.ndarray
    intervals: int
    gcv: float


class _BinMoments(NamedTuple):
    """One pass over a region's pixels: per-bin sums, and what the residuals need."""

    low: float
    high: float
    bins: int
    occupied: np.ndarray  # (m,) bins holding pixels, ascending
    counts: np.ndarray  # (m,) pixels per occupied bin
    means: np.ndarray  # (m,) mean log variance per occupied bin
    powers: np.ndarray  # (7, m) sums of v^k
    cross: np.ndarray  # (4, m) sums of (y - bin mean) v^k
    squares: np.ndarray  # (m,) sums of (y - bin mean)^2
    index: np.ndarray  # (n,) each pixel's bin
    local: np.ndarray  # (n,) each pixel's position v in [-1, 1] in its bin
    centred: np.ndarray  # (n,) y - its bin's mean


class _Bins(NamedTuple):
    """What the binning of :math:`x` alone gives (:func:`_bins`): shared by every fit on the
    same intensities (the rounds of :func:`stereovar.controls.covariates.fit_control`)."""

    low: float
    high: float
    bins: int
    occupied: np.ndarray
    counts: np.ndarray
    powers: np.ndarray
    index: np.ndarray
    local: np.ndarray


def _bins(x: np.ndarray) -> _Bins:
    """Bin :math:`x` into equal bins over :math:`[\\min x, \\max x]` (:data:`BINS`) and sum,
    per bin, :math:`v^k` (:math:`k \\le 6`), with :math:`v \\in [-1, 1]` the position in
    the bin."""
    low, high = float(x.min()), float(x.max())
    bins = int(min(BINS, max(256, x.size // 4)))
    pos = x - low
    pos *= bins / (high - low)
    index = pos.astype(np.intp)
    np.minimum(index, bins - 1, out=index)
    local = pos
    local -= index
    local *= 2.0
    local -= 1.0
    counts = np.bincount(index, minlength=bins).astype(np.float64)
    occupied = np.flatnonzero(counts)

    def sums(weights):
        return np.bincount(index, weights, minlength=bins)[occupied]

    counts = counts[occupied]
    square = local * local
    cube = square * local
    product = np.empty_like(local)
    powers = np.empty((7, occupied.size))
    powers[0], powers[1], powers[2], powers[3] = counts, sums(local), sums(square), sums(cube)
    for k, (p, q) in zip((4, 5, 6), ((square, square), (square, cube), (cube, cube)), strict=True):
        powers[k] = sums(np.multiply(p, q, out=product))
    return _Bins(low, high, bins, occupied, counts, powers, index, local)


def _bin_moments(x: np.ndarray, y: np.ndarray, binned: _Bins | None = None) -> _BinMoments:
    """Bin :math:`x` (:func:`_bins`, or ``binned`` from an earlier call on the same
    :math:`x`) and sum, per bin, :math:`\\tilde y v^k` (:math:`k \\le 3`) and
    :math:`\\tilde y^2`, with :math:`\\tilde y` the log variance minus its bin's mean (which
    keeps the sums small, so a residual sum of squares near the float32 floor of an Eq. 1
    field is still resolved)."""
    low, high, bins, occupied, counts, powers, index, local = binned or _bins(x)

    def sums(weights):
        return np.bincount(index, weights, minlength=bins)[occupied]

    means = np.zeros(bins)
    means[occupied] = sums(y) / counts
    centred = y - means[index]
    square = local * local
    cube = square * local
    product = np.empty_like(local)
    cross = np.zeros((4, occupied.size))  # row 0, the sum of y - mean, is 0 in every bin
    for r, p in zip((1, 2, 3), (local, square, cube), strict=True):
        cross[r] = sums(np.multiply(centred, p, out=product))
    squares = sums(np.multiply(centred, centred, out=product))
    return _BinMoments(
        low, high, bins, occupied, counts, means[occupied], powers, cross, squares,
        index, local, centred,
    )  # fmt: skip


def _knots(moments: _BinMoments, intervals: int) -> np.ndarray:
    """Cubic-spline knot vector of at most ``intervals`` intervals, interior knots on bin
    edges.

    Interior knots are the ``k / intervals`` quantiles of an equal mixture of the pixels'
    distribution of :math:`\\ln\\mu` and the uniform one over the occupied bins: dense where
    the pixels are, yet never further apart than twice the occupied range over ``intervals``
    in the sparse tails, where the read-noise knee of :math:`a\\mu + b` bends. Each knot is
    the right edge of an occupied bin, so every interval holds pixels.
    """
    occupied, counts = moments.occupied, moments.counts
    mixture = 0.5 * np.cumsum(counts) / counts.sum()
    mixture += 0.5 * np.arange(1, occupied.size + 1) / occupied.size
    chosen = np.searchsorted(mixture, np.arange(1, intervals) / intervals)
    edges = np.unique(occupied[np.minimum(chosen, occupied.size - 1)] + 1)
    edges = edges[edges < moments.bins]
    inner = moments.low + edges * ((moments.high - moments.low) / moments.bins)
    return np.concatenate([[moments.low] * 4, inner, [moments.high] * 4])


class _Level(NamedTuple):
    """One resolution: the knots, each interval's B-spline pieces and where each bin sits."""

    knots: np.ndarray
    first: np.ndarray  # (K,) each interval's first active B-spline
    pieces: np.ndarray  # (K, 4, 4) active coefficients to the interval's cubic in s
    interval: np.ndarray  # (m,) each occupied bin's interval
    shift: np.ndarray  # (m,) a bin's v maps to s = shift + scale v
    scale: np.ndarray  # (m,)


def _level(moments: _BinMoments, intervals: int) -> _Level:
    """The cubic B-splines on :func:`_knots` as cubics in each interval's own coordinate
    :math:`s \\in [-1, 1]`, and each bin's place in its interval."""
    knots = _knots(moments, intervals)
    breaks = knots[3:-3]
    mids, halves = (breaks[1:] + breaks[:-1]) / 2, (breaks[1:] - breaks[:-1]) / 2
    nodes = (mids[:, None] + halves[:, None] * _NODES).reshape(-1)
    design = BSpline.design_matrix(nodes, knots, 3)
    pieces = np.matmul(_TO_MONOMIAL, design.data.reshape(-1, 4, 4))  # interval, power, spline
    width = (moments.high - moments.low) / moments.bins
    centres = moments.low + (moments.occupied + 0.5) * width
    interval = np.searchsorted(breaks[1:-1], centres)
    shift = (centres - mids[interval]) / halves[interval]
    scale = (0.5 * width) / halves[interval]
    return _Level(knots, design.indices[::16], pieces, interval, shift, scale)


def _moments_in_intervals(rows: np.ndarray, level: _Level) -> np.ndarray:
    """Per-bin sums of :math:`w v^k` (rows :math:`k`) to per-bin sums of :math:`w s^k`:
    :math:`s^k = \\sum_{i \\le k} \\binom{k}{i} a^{k-i} c^i v^i` for
    :math:`s = a + c v`."""
    order = rows.shape[0]
    shifts = [np.ones_like(level.shift), level.shift]
    scaled = [rows[0], rows[1] * level.scale]
    for _ in range(2, order):
        shifts.append(shifts[-1] * level.shift)
        scaled.append(rows[len(scaled)] * level.scale ** len(scaled))
    out = np.empty_like(rows)
    for k in range(order):
        out[k] = scaled[k]
        for i in range(k):
            out[k] += _BINOMIAL[k, i] * shifts[k - i] * scaled[i]
    return out


def _penalised_gram(first, blocks, size: int) -> np.ndarray:
    """Upper banded form (4, size) of :math:`\\sum_j P_j^\\top H_j P_j` plus the
    :data:`PENALTY` second-difference penalty."""
    banded = np.zeros((4, size))
    for r in range(4):
        for s in range(r, 4):
            banded[3 - s + r] += np.bincount(first + s, blocks[:, r, s], minlength=size)
    weight = PENALTY * banded[3].mean()  # size >= 4: a cubic spline has 4 coefficients or more
    diagonal = np.full(size, 6.0)
    diagonal[[0, -1]], diagonal[[1, -2]] = 1.0, 5.0
    upper = np.full(size - 1, -4.0)
    upper[[0, -1]] = -2.0
    banded[3] += weight * diagonal
    banded[2, 1:] += weight * upper
    banded[1, 2:] += weight
    return banded


def _fit(moments: _BinMoments, level: _Level) -> tuple[np.ndarray, float]:
    """Least-squares spline of one level: its B-spline coefficients and the residual sum of
    squares over the pixels, from the bins' sums gathered per knot interval (in the
    interval's coordinate, about the interval's mean log variance)."""
    size, k = level.knots.size - 4, level.pieces.shape[0]
    where = level.interval
    powers = _moments_in_intervals(moments.powers, level)
    cross = _moments_in_intervals(moments.cross, level)
    counts = np.bincount(where, moments.counts, k)
    means = np.bincount(where, moments.counts * moments.means, k) / counts
    offset = moments.means - means[where]  # each bin's mean about its interval's
    cross += offset * powers[:4]
    squares = np.bincount(where, moments.squares + moments.counts * offset * offset, k).sum()
    hankel = np.stack([np.bincount(where, row, k) for row in powers], axis=-1)[:, _HANKEL]
    cross = np.stack([np.bincount(where, row, k) for row in cross], axis=-1)
    pieces_t = level.pieces.transpose(0, 2, 1)
    blocks = pieces_t @ hankel @ level.pieces
    target = cross + means[:, None] * hankel[:, :, 0]
    rhs_blocks = np.matmul(pieces_t, target[:, :, None])[:, :, 0]
    active = level.first[:, None] + np.arange(4)
    rhs = np.bincount(active.reshape(-1), rhs_blocks.reshape(-1), minlength=size)
    banded = _penalised_gram(level.first, blocks, size)
    try:
        beta = solveh_banded(banded, rhs, check_finite=False)
    except LinAlgError:  # a layout the penalty leaves singular: a ridge settles it
        banded[3] += 1e-9 * banded[3].max()
        beta = solveh_banded(banded, rhs, check_finite=False)
    local = np.matmul(level.pieces, beta[active][:, :, None])[:, :, 0]
    local[:, 0] -= means
    quadratic = np.matmul(hankel, local[:, :, None])[:, :, 0]
    rss = squares - 2.0 * np.einsum("ji,ji->", local, cross)
    rss += np.einsum("ji,ji->", local, quadratic)
    return beta, max(float(rss), 0.0)


def _resolutions(n: int, intervals: int | None) -> list[int]:
    """The knot-interval counts tried: 1, 2, 4, ... up to :data:`MAX_INTERVALS` and
    :data:`MIN_PIXELS_PER_INTERVAL` pixels per interval, or ``intervals`` alone."""
    if intervals is not None:
        return [max(1, int(intervals))]
    top = max(1, min(MAX_INTERVALS, n // MIN_PIXELS_PER_INTERVAL))
    return [1 << j for j in range(top.bit_length())]


def _evaluate(moments: _BinMoments, level: _Level, beta: np.ndarray) -> np.ndarray:
    """Residuals pixel by pixel: each bin's cubic in :math:`v` (the interval's cubic at
    :math:`s = a + c v`, less the bin's mean) subtracted from :math:`\\tilde y` (Horner)."""
    active = level.first[:, None] + np.arange(4)
    coefficients = np.matmul(level.pieces, beta[active][:, :, None])[:, :, 0]  # (K, power)
    per_bin = coefficients[level.interval].T  # (power of s, m)
    shifts = level.shift[None, :] ** np.arange(4)[:, None]
    table = np.zeros((4, moments.bins))
    for i in range(4):
        term = sum(_BINOMIAL[k, i] * shifts[k - i] * per_bin[k] for k in range(i, 4))
        table[i, moments.occupied] = term * level.scale**i
    table[0, moments.occupied] -= moments.means
    v = moments.local
    fitted = table[3][moments.index]
    for r in (2, 1, 0):
        fitted *= v
        fitted += table[r][moments.index]
    return np.subtract(moments.centred, fitted, out=fitted)


def fit_intensity(log_variance, log_intensity, *, intervals: int | None = None) -> IntensityFit:
    """The conditional mean of :math:`\\ln\\sigma^2` given :math:`\\ln\\mu`, removed.

    .. math::

        \\ln \\sigma^2_i = \\hat g_K(\\ln \\mu_i) + e_i, \\qquad
        \\hat g_K = \\arg\\min_{g \\in S_K} \\sum_i \\bigl(\\ln\\sigma^2_i - g(\\ln\\mu_i)\\bigr)^2,
        \\qquad
        K = \\arg\\min_{K'} \\mathrm{GCV}(K') =
            \\arg\\min_{K'} \\frac{n\\, \\mathrm{RSS}_{K'}}{(n - K' - 3)^2},

    with :math:`S_K` the cubic splines (:math:`K + 3` B-spline coefficients) on
    :math:`K` knot intervals of :math:`\\ln\\mu` (knots at quantiles of the pixels mixed
    with equal spacing over their range) and :math:`K` tried over
    :math:`1, 2, 4, \\ldots` up to :data:`MAX_INTERVALS` and
    :data:`MIN_PIXELS_PER_INTERVAL` pixels per interval, stopping after two doublings
    that do not lower the score. The intensity control, not in the paper; Eq. 3 (paper
    Sec. 2.3) on the residuals of both views is :func:`stereovar.controls.partial.partial_pair`.

    Why this shape. Whatever :math:`\\hat g` misses of the true conditional mean is a
    function of :math:`\\mu`, which both views share once aligned, so the two views'
    misfits correlate and read as a cue: a global cubic leaves a partial :math:`\\rho` of
    0.6-0.98 on a variance that is exactly :math:`a\\mu + b`. A spline's misfit falls as
    its knots close up; generalised cross-validation (Craven and Wahba 1979, the closed
    form of leave-one-out cross-validation for a linear smoother) stops refining where the
    misfit drops below the estimation noise of :math:`\\ln\\sigma^2`, where it adds
    roughly :math:`(K + 3)/n` to the correlation, and a field with no noise
    (``equalise``'s, exactly :math:`a\\mu + b`) gets the finest spline, which follows
    :math:`\\ln(a\\mu + b)` to within float32 rounding. GCV needs no random split of the
    pixels into folds, so the result does not depend on their order. Structure that is not
    a function of :math:`\\mu` (the Monte Carlo pattern the statistic looks for) stays in
    the residuals; a cubic piece spans at least :data:`MIN_PIXELS_PER_INTERVAL` pixels.

    Computation: :math:`\\ln\\mu` is cut into :data:`BINS` equal bins and knots are put on
    bin edges, so :math:`\\hat g` is one cubic in each bin and the least-squares problem is
    exact in the bins' moments (one pass over the pixels); each
    resolution then costs :math:`O(\\text{bins})`, and the normal equations are banded.
    A second-difference penalty of relative weight :data:`PENALTY` only settles
    coefficients the data leave free (few distinct intensities: with :math:`d \\le 3`
    of them the fit is each level's mean).

    Parameters
    ----------
    log_variance, log_intensity : numpy.ndarray, shape (n,)
        :math:`\\ln\\sigma^2` and :math:`\\ln\\mu` of one view over one region.
    intervals : int, keyword-only, optional
        Use this many knot intervals instead of choosing (1: one cubic over the range).

    Returns
    -------
    IntensityFit
    """
    y = np.asarray(log_variance, dtype=np.float64).reshape(-1)
    x = np.asarray(log_intensity, dtype=np.float64).reshape(-1)
    if y.shape != x.shape:
        raise ValueError(f"log_variance has {y.size} values, log_intensity {x.size}")
    finite = np.isfinite(x) & np.isfinite(y)
    if not finite.all():
        out = np.full(y.shape, np.nan)
        inner = fit_intensity(y[finite], x[finite], intervals=intervals)
        out[finite] = inner.residuals
        return inner._replace(residuals=out)
    n = y.size
    if n < MIN_PIXELS:
        return IntensityFit(np.full(y.shape, np.nan), 0, float("nan"))
    if not x.max() - x.min() > 1e-9 * max(1.0, float(np.abs(x).max())):
        # one intensity (to 1e-9, below float32's resolution): its mean is the conditional mean
        residuals = y - y.mean()
        return IntensityFit(residuals, 0, n * float(residuals @ residuals) / (n - 1) ** 2)
    return _fit_binned(y, x, intervals)


def _fit_binned(y, x, intervals, binned: _Bins | None = None, levels: dict | None = None):
    """:func:`fit_intensity` on finite :math:`x` with a spread, reusing ``binned``
    (:func:`_bins` of ``x``) and ``levels`` (resolution to :func:`_level`, filled here) from
    earlier fits on the same :math:`x`."""
    n = y.size
    moments = _bin_moments(x, y, binned)
    levels = {} if levels is None else levels
    best, since_best = None, 0
    for k in _resolutions(n, intervals):
        level = levels.get(k)
        if level is None:
            level = levels[k] = _level(moments, k)
        beta, rss = _fit(moments, level)
        score = n * rss / max(n - beta.size, 1) ** 2
        if best is None or score < best[0]:
            best, since_best = (score, k, level, beta), 0
        else:
            since_best += 1
            if since_best == 2:
                break
    score, _, level, beta = best
    return IntensityFit(_evaluate(moments, level, beta), beta.size - 3, float(score))


def intensity_fitter(log_intensity):
    """:func:`fit_intensity` as a function of the log variance alone, for many fits on the
    same intensities: the binning of :math:`\\ln\\mu` and each resolution's knots are
    computed once (the same numbers as separate calls).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> log_mu = rng.uniform(-3, 0, 2000)
    >>> fit = intensity_fitter(log_mu)
    >>> for shift in (0.0, 0.5):
    ...     y = np.log(0.01 * np.exp(log_mu) + 1e-4) + shift + rng.normal(0, 0.1, 2000)
    ...     assert np.array_equal(fit(y).residuals, fit_intensity(y, log_mu).residuals)
    """
    x = np.asarray(log_intensity, dtype=np.float64).reshape(-1)
    state: dict = {}

    def fit(log_variance) -> IntensityFit:
        y = np.asarray(log_variance, dtype=np.float64).reshape(-1)
        spread = x.max() - x.min() > 1e-9 * max(1.0, float(np.abs(x).max())) if x.size else False
        if (y.shape != x.shape or x.size < MIN_PIXELS or not spread
                or not (np.isfinite(x).all() and np.isfinite(y).all())):
            return fit_intensity(y, x)
        if "bins" not in state:
            state["bins"], state["levels"] = _bins(x), {}
        return _fit_binned(y, x, None, state["bins"], state["levels"])

    return fit


def intensity_residuals(log_variance, log_intensity, *, intervals: int | None = None):
    """Residuals of :math:`\\ln\\sigma^2` after its conditional mean given :math:`\\ln\\mu`.

    .. math::

        e_i = \\ln \\sigma^2_i - \\hat g(\\ln \\mu_i), \\qquad
        \\hat g \\approx \\mathrm E\\bigl[\\ln\\sigma^2 \\mid \\ln\\mu\\bigr],

    with :math:`\\hat g` the least-squares cubic spline whose number of knots
    generalised cross-validation chooses (:func:`fit_intensity`, which also reports the
    resolution). The intensity control, not in the paper;
    :func:`stereovar.controls.partial.partial_pair` correlates the two views' residuals by
    Eq. 3 (paper Sec. 2.3).

    Parameters
    ----------
    log_variance, log_intensity : numpy.ndarray, shape (n,)
        Values of one view over one region.
    intervals : int, keyword-only, optional
        Fixed number of knot intervals (default: chosen from the data).

    Returns
    -------
    numpy.ndarray, shape (n,)
        NaN where an input is not finite; everywhere when fewer than :data:`MIN_PIXELS`
        are.

    Examples
    --------
    A log variance that is a cubic in :math:`\\ln\\mu` is explained entirely (nine pixels
    allow one cubic piece):

    >>> import numpy as np
    >>> log_mu = np.linspace(-2.0, 2.0, 9)
    >>> e = intensity_residuals(0.5 + log_mu - 0.25 * log_mu**3, log_mu)
    >>> bool(np.allclose(e, 0.0))
    True

    So is a camera's :math:`\\ln(a\\mu + b)` over 20 000 pixels spanning the read-noise
    knee, which no cubic follows (its misfit is a function of :math:`\\mu` that both views
    would share):

    >>> log_mu = np.linspace(-9.0, 1.0, 20_000)
    >>> camera = np.log(1e-3 * np.exp(log_mu) + 4e-6)
    >>> cubic = np.polynomial.Polynomial.fit(log_mu, camera, 3)
    >>> bool(np.abs(camera - cubic(log_mu)).max() > 0.05)
    True
    >>> bool(np.abs(intensity_residuals(camera, log_mu)).max() < 1e-6)
    True
    """
    return fit_intensity(log_variance, log_intensity, intervals=intervals).residuals


def relative_variance(variance, intensity) -> np.ndarray:
    """Relative variance :math:`\\sigma^2 / \\mu^2`, which removes albedo; NaN where
    :math:`\\mu \\le 0`.

    .. math:: v_{\\text{rel}}(x, y) = \\frac{\\sigma^2(x, y)}{\\mu(x, y)^2}
    """
    var = np.asarray(variance, dtype=np.float64)
    mu = np.asarray(intensity, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(mu > 0, var / (mu * mu), np.nan)
