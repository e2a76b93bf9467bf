"""The colour and position terms of the intensity control.

A camera's noise variance depends on more than the brightness of a pixel. White balance,
a colour matrix or a per-channel law make it depend on the pixel's colour at a fixed
brightness; lens-shading correction and fixed gain maps make it depend on where the pixel
sits on the sensor. Both views share those dependencies at corresponding pixels (the same
surface colour, nearly the same sensor position at small disparities), so a control that
sees only :math:`\\ln\\mu` leaves them in its residuals, where they read as a Monte Carlo
cue. This module removes them beside the spline in :math:`\\ln\\mu`
(:func:`stereovar.controls.intensity.fit_intensity`): an additive model

.. math::

    \\ln\\sigma^2_i = g(\\ln\\bar\\mu_i) + h_c(r_i) + h_p(x_i, y_i) + e_i

with :math:`r = (\\mu_R, \\mu_B)/\\bar\\mu` the pixel's chromaticity and :math:`(x, y)` its
position on its own sensor, :math:`h_c` and :math:`h_p` polynomials whose degrees
generalised cross-validation chooses. Frames stored as integers add a third polynomial,
:math:`h_q(\\ln q_i)`, in the variance their encoding implies at the pixel's seed mean
(:mod:`stereovar.controls.quantisation`). Why additive: for shot noise through per-channel gains
:math:`w_c` (white balance), a colour matrix or a per-channel power law,
:math:`\\sigma^2 = \\bar\\mu\\, f(r)` exactly; through a gain :math:`G(x, y)` over the sensor,
:math:`\\sigma^2 = G\\, a\\mu`; the logarithm separates each.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from typing import NamedTuple

import numpy as np
from numpy.polynomial import legendre
from scipy.linalg import solve

POSITION_DEGREES = (0, 2, 4, 6, 8)
"""Total degrees of the position polynomial tried (0: none). Degree 8 follows a lens-shading
gain of 4x from the centre to the corners to within a percent, yet has 44 coefficients: it
cannot follow a pattern finer than about a ninth of the image."""

COLOUR_DEGREES = (0, 1, 2, 3)
"""Total degrees of the chromaticity polynomial tried (0: none)."""

QUANTISATION_DEGREES = (0, 1, 2, 3)
"""Degrees of the polynomial in :math:`\\ln q` tried (0: none)."""

BACKFIT_ROUNDS = 2
"""Rounds of backfitting: the spline in :math:`\\ln\\bar\\mu` refitted on what the
polynomials leave, and the polynomials on what the spline leaves."""

QUANTISED_BACKFIT_ROUNDS = 40
"""Most rounds of backfitting when the quantisation term is used: it runs until a round
lowers the residual sum of squares by less than :data:`BACKFIT_TOLERANCE` of it (on 8-bit
frames at 0.2 DN of noise, two rounds leave a residual variance of 0.108, ten 0.022,
twenty 0.019)."""

BACKFIT_TOLERANCE = 3e-3
"""The relative drop of the residual sum of squares below which backfitting stops."""


class ControlFit(NamedTuple):
    """The intensity control of one view with its colour and position terms
    (:func:`fit_control`).

    Attributes
    ----------
    residuals : numpy.ndarray (n,)
    intervals : int
        Knot intervals of the spline in :math:`\\ln\\bar\\mu`.
    colour_degree, position_degree : int
        Degrees chosen (0: the term is not used).
    gcv : float
    quantisation_degree : int
        Degree of the quantisation term chosen (0: not used, or float frames).
    """

    residuals: np.ndarray
    intervals: int
    colour_degree: int
    position_degree: int
    gcv: float
    quantisation_degree: int = 0


def _unit(values: np.ndarray) -> np.ndarray:
    """``values`` mapped onto :math:`[-1, 1]` over their range (0 for a constant)."""
    low, high = float(values.min()), float(values.max())
    if not high > low:
        return np.zeros_like(values)
    return (2.0 * values - (low + high)) / (high - low)


def _total_degree(u: np.ndarray, v: np.ndarray, degree: int) -> tuple[np.ndarray, list]:
    """Columns :math:`P_i(u) P_j(v)` for :math:`1 \\le i + j \\le` ``degree`` (Legendre
    polynomials, no constant) and each column's total degree."""
    pu = legendre.legvander(u, degree)
    pv = legendre.legvander(v, degree)
    pairs = [(i, total - i) for total in range(1, degree + 1) for i in range(total + 1)]
    columns = np.empty((u.size, len(pairs)))
    for k, (i, j) in enumerate(pairs):
        np.multiply(pu[:, i], pv[:, j], out=columns[:, k])
    return columns, [i + j for i, j in pairs]


POSITION_CACHE_SIZE = 4
"""Position blocks kept (:func:`_position_block`): both views of a scene's two largest
regions, whose pixels every replicate of the calibration shares."""

_POSITION_CACHE: OrderedDict = OrderedDict()


def _position_block(position, degree: int) -> tuple[np.ndarray, list, np.ndarray]:
    """The centred position columns of a pixel set, their degrees and their Gram matrix,
    kept for the next call on the same pixels (the same coordinates, by a digest of their
    bytes)."""
    x = np.ascontiguousarray(position[0], dtype=np.float64)
    y = np.ascontiguousarray(position[1], dtype=np.float64)
    key = (degree, x.size, hashlib.blake2b(x.tobytes() + y.tobytes(), digest_size=16).digest())
    hit = _POSITION_CACHE.get(key)
    if hit is None:
        z, deg = _total_degree(_unit(x), _unit(y), degree)
        z -= z.mean(axis=0)
        hit = (z, deg, z.T @ z)
        _POSITION_CACHE[key] = hit
        while len(_POSITION_CACHE) > POSITION_CACHE_SIZE:
            _POSITION_CACHE.popitem(last=False)
    else:
        _POSITION_CACHE.move_to_end(key)
    return hit


class Columns:
    """Candidate columns of :math:`h_c`, :math:`h_p` and :math:`h_q`, kept as their three
    blocks (never joined into one array as large as the region times every column: the
    position block is shared between calls, :func:`_position_block`).

    Parameters
    ----------
    blocks : sequence of numpy.ndarray (n, p_b)
    """

    def __init__(self, blocks):
        self.blocks = [b for b in blocks if b.shape[1]]

    @property
    def shape(self) -> tuple[int, int]:
        n = self.blocks[0].shape[0] if self.blocks else 0
        return n, sum(b.shape[1] for b in self.blocks)

    def take(self, use: np.ndarray) -> Columns:
        """The columns at ``use`` (increasing): a block's leading columns stay a view."""
        out, start = [], 0
        use = np.asarray(use)
        for b in self.blocks:
            mine = use[(use >= start) & (use < start + b.shape[1])] - start
            start += b.shape[1]
            if mine.size == 0:
                continue
            prefix = mine.size and mine[-1] == mine.size - 1
            out.append(b[:, : mine.size] if prefix else b[:, mine])
        return Columns(out)

    def rmatvec(self, y: np.ndarray) -> np.ndarray:
        """:math:`Z^\\top y`."""
        if not self.blocks:
            return np.empty(0)
        return np.concatenate([b.T @ y for b in self.blocks])

    def matvec(self, beta: np.ndarray) -> np.ndarray:
        """:math:`Z \\beta`."""
        out, start = np.zeros(self.shape[0]), 0
        for b in self.blocks:
            out += b @ beta[start : start + b.shape[1]]
            start += b.shape[1]
        return out


def design(colour, position, quantisation=None, *, colour_degree=COLOUR_DEGREES[-1],
           position_degree=POSITION_DEGREES[-1],
           quantisation_degree=QUANTISATION_DEGREES[-1]):
    """Every candidate column of :math:`h_c`, :math:`h_p` and :math:`h_q`, centred, with
    each column's degree in its term and their Gram matrix.

    Parameters
    ----------
    colour : tuple of numpy.ndarray (n,) or None
        The two chromaticity coordinates :math:`\\mu_R/\\bar\\mu`, :math:`\\mu_B/\\bar\\mu`.
    position : tuple of numpy.ndarray (n,) or None
        :math:`(x, y)` on the view's own sensor, in pixels.
    quantisation : numpy.ndarray (n,) or None
        :math:`q`, the variance the encoding implies
        (:func:`stereovar.controls.quantisation.quantisation_variance`;
        :func:`_quantisation_block`).

    Returns
    -------
    columns : Columns
        :math:`Z`, (n, p), in the order chromaticity, position, quantisation.
    degrees : numpy.ndarray (3, p)
        Each column's degree in the chromaticity, position and quantisation terms (0 in the
        others).
    gram : numpy.ndarray (p, p)
        :math:`Z^\\top Z` of the columns.
    """
    n = next((len(t[0]) for t in (colour, position) if t is not None),
             0 if quantisation is None else len(quantisation))
    c = np.empty((n, 0))
    cdeg: list = []
    if colour is not None:
        c, cdeg = _total_degree(_unit(np.asarray(colour[0], float)),
                                _unit(np.asarray(colour[1], float)), colour_degree)
        c -= c.mean(axis=0)
    p, pdeg, pp = (np.empty((n, 0)), [], np.empty((0, 0))) if position is None else (
        _position_block(position, position_degree))
    q, qdeg = np.empty((n, 0)), []
    if quantisation is not None:
        q = _quantisation_block(quantisation, quantisation_degree)
        qdeg = [1] + list(range(1, quantisation_degree + 1))
    # Z'Z by blocks: the position block's own (most of the columns) is the pixel set's, kept
    cq = np.concatenate([c, q], axis=1)
    cross = cq.T @ p
    inner = cq.T @ cq
    k = c.shape[1]
    order = np.r_[0:k, cq.shape[1]:cq.shape[1] + p.shape[1], k:cq.shape[1]]  # c, p, q
    gram = np.block([[inner, cross], [cross.T, pp]])
    gram = gram[np.ix_(order, order)] if q.shape[1] else gram
    blocks = (cdeg, list(pdeg), qdeg)
    degrees = np.zeros((3, gram.shape[0]), dtype=int)
    start = 0
    for term, block in enumerate(blocks):
        degrees[term, start:start + len(block)] = block
        start += len(block)
    columns = Columns([c, p, q])
    # a term the region holds constant (a grey scene's chromaticity, float frames'
    # quantisation) has nothing to fit
    diagonal = np.diag(gram)
    keep = diagonal > 1e-12 * max(float(diagonal.max(initial=0.0)), 1e-300)
    if not keep.all():
        kept = np.flatnonzero(keep)
        columns, degrees, gram = columns.take(kept), degrees[:, kept], gram[np.ix_(kept, kept)]
    return columns, degrees, gram


def _quantisation_block(quantisation, degree: int) -> np.ndarray:
    """Centred columns of :math:`h_q`: the indicator of :math:`q = 0` (every frame on one
    code: Eq. 1 gives exactly 0, which the two logarithms floor at different values), then
    Legendre polynomials of degree 1 to ``degree`` in :math:`\\ln q` (floored at its
    smallest positive value)."""
    from ..statistics.robust import log_floor

    q = np.asarray(quantisation, dtype=np.float64).reshape(-1)
    logs, _ = log_floor(q)
    columns = np.concatenate(
        [(q <= 0).astype(np.float64)[:, None],
         legendre.legvander(_unit(logs), degree)[:, 1:]], axis=1)
    return columns - columns.mean(axis=0)


def _solve(gram: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Least-squares coefficients from the normal equations, with a ridge of 1e-10 of the
    mean diagonal (columns the region leaves collinear get 0, not a failure)."""
    if not rhs.size:
        return rhs
    ridged = gram.copy()
    ridged.flat[:: gram.shape[0] + 1] += 1e-10 * max(float(np.trace(gram)) / gram.shape[0],
                                                      1e-300)
    return solve(ridged, rhs, assume_a="pos", check_finite=False)


def _gram(columns: Columns) -> np.ndarray:
    """:math:`Z^\\top Z` of columns kept by blocks."""
    joined = np.concatenate(columns.blocks, axis=1) if columns.blocks else np.empty((0, 0))
    return joined.T @ joined


def choose_degrees(residuals, columns, degrees, *, spline_df: int = 0, gram=None):
    """The degrees of :math:`h_c`, :math:`h_p` and :math:`h_q` that minimise the generalised
    cross-validation score of the polynomials fitted to ``residuals``.

    .. math::

        (d_c, d_p, d_q) = \\arg\\min \\frac{n\\,\\mathrm{RSS}(d_c, d_p, d_q)}
            {(n - k_0 - p(d_c, d_p, d_q))^2}

    with :math:`p` the columns of degree up to :math:`d_c` (chromaticity), :math:`d_p`
    (position) and :math:`d_q` (quantisation), and :math:`k_0` the spline's coefficients.

    Parameters
    ----------
    degrees : numpy.ndarray (3, p)
        Each column's degree in the three terms (:func:`design`).

    Returns
    -------
    tuple of int
        :math:`(d_c, d_p, d_q)`.
    """
    import itertools

    y = np.asarray(residuals, dtype=np.float64)
    n = y.size
    columns = columns if isinstance(columns, Columns) else Columns([np.asarray(columns)])
    gram = _gram(columns) if gram is None else gram
    rhs = columns.rmatvec(y)
    yy = float(y @ y)
    best = None
    grids = [sorted({0, *row.tolist()}) for row in np.asarray(degrees).reshape(3, -1)]
    for chosen in itertools.product(*grids):
        use = np.flatnonzero((degrees <= np.asarray(chosen)[:, None]).all(axis=0))
        beta = _solve(gram[np.ix_(use, use)], rhs[use])
        rss = max(yy - float(beta @ rhs[use]), 0.0)
        dof = n - spline_df - use.size
        if dof <= 0:
            continue
        score = n * rss / dof**2
        if best is None or score < best[0]:
            best = (score, chosen)
    return tuple(int(d) for d in best[1]) if best is not None else (0, 0, 0)


def fit_control(log_variance, log_intensity, *, colour=None, position=None,
                quantisation=None) -> ControlFit:
    """The intensity control with its colour and position terms, removed.

    .. math::

        e_i = \\ln\\sigma^2_i - \\hat g(\\ln\\bar\\mu_i) - \\hat h_c(r_i) - \\hat h_p(x_i, y_i)

    fitted by backfitting (:data:`BACKFIT_ROUNDS` rounds): the spline :math:`\\hat g`
    (:func:`stereovar.controls.intensity.fit_intensity`, its knots by generalised
    cross-validation) on :math:`\\ln\\sigma^2 - \\hat h_c - \\hat h_p`, and the polynomials
    by least squares on :math:`\\ln\\sigma^2 - \\hat g`; their degrees are chosen once, by
    :func:`choose_degrees` on the first spline's residuals. Not in the paper: the control
    that Eq. 3 (paper Sec. 2.3) reads in the ``partial`` statistic.

    Parameters
    ----------
    log_variance, log_intensity : numpy.ndarray (n,)
        :math:`\\ln\\sigma^2` and :math:`\\ln\\bar\\mu` of one view over one region (finite).
    colour : tuple of numpy.ndarray (n,), optional
        :math:`(\\mu_R/\\bar\\mu, \\mu_B/\\bar\\mu)`.
    position : tuple of numpy.ndarray (n,), optional
        The pixels' :math:`(x, y)` on this view's sensor.
    quantisation : numpy.ndarray (n,), optional
        The variance the frames' integer encoding implies at each pixel's seed mean
        (:func:`stereovar.controls.quantisation.quantisation_variance`): whether it is 0,
        and its logarithm, enter the model.

    Returns
    -------
    ControlFit

    Examples
    --------
    Shot noise through white-balance gains (2, 1, 1.6): at one brightness a red pixel is
    noisier than a blue one, which :math:`\\ln\\bar\\mu` alone cannot say. With the
    chromaticity the variance is explained:

    >>> import numpy as np
    >>> from stereovar.controls.intensity import intensity_residuals
    >>> rng = np.random.default_rng(0)
    >>> raw = rng.uniform(0.05, 1.0, (4000, 3))
    >>> mu = raw * [2.0, 1.0, 1.6]
    >>> log_var = np.log((mu * [2.0, 1.0, 1.6] * 1e-3).mean(axis=1))
    >>> log_mu = np.log(mu.mean(axis=1))
    >>> ratios = (mu[:, 0] / mu.mean(axis=1), mu[:, 2] / mu.mean(axis=1))
    >>> bool(np.std(intensity_residuals(log_var, log_mu)) > 0.05)
    True
    >>> fit = fit_control(log_var, log_mu, colour=ratios)
    >>> bool(np.std(fit.residuals) < 0.005), fit.colour_degree > 0
    (True, True)
    """
    from .intensity import intensity_fitter

    y = np.asarray(log_variance, dtype=np.float64).reshape(-1)
    x = np.asarray(log_intensity, dtype=np.float64).reshape(-1)
    fit_intensity = intensity_fitter(x)  # every round bins the same intensities
    first = fit_intensity(y)
    if quantisation is not None and not (np.asarray(quantisation) > 0).any():
        quantisation = None  # float frames, or no pixel between two codes
    if (colour is None and position is None and quantisation is None) or not np.isfinite(
            first.residuals).all():
        return ControlFit(first.residuals, first.intervals, 0, 0, first.gcv)
    columns, degrees, full_gram = design(colour, position, quantisation)
    chosen = choose_degrees(first.residuals, columns, degrees,
                            spline_df=first.intervals + 3, gram=full_gram)
    dc, dp, dq = chosen
    use = np.flatnonzero((degrees <= np.asarray(chosen)[:, None]).all(axis=0))
    if not use.size:
        return ControlFit(first.residuals, first.intervals, 0, 0, first.gcv)
    z = columns.take(use) if use.size < columns.shape[1] else columns
    gram = full_gram[np.ix_(use, use)]
    spline_part = y - first.residuals
    fit = first
    # the quantisation term is nearly collinear with the spline (a code's step grows with
    # the intensity), so backfitting converges slowly there: run it to convergence
    rounds = BACKFIT_ROUNDS if dq == 0 else QUANTISED_BACKFIT_ROUNDS
    previous = np.inf
    for _ in range(rounds):
        beta = _solve(gram, z.rmatvec(y - spline_part))
        poly = z.matvec(beta)
        fit = fit_intensity(y - poly)
        spline_part = y - poly - fit.residuals
        rss = float(fit.residuals @ fit.residuals)
        if dq and previous - rss <= BACKFIT_TOLERANCE * rss:
            break
        previous = rss
    residuals = fit.residuals
    n = y.size
    dof = max(n - fit.intervals - 3 - use.size, 1)
    return ControlFit(residuals, fit.intervals, dc, dp, n * float(residuals @ residuals) / dof**2,
                      dq)
