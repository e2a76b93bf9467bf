"""The intensity-controlled pair: what each view's variance keeps once intensity, colour,
position and the encoding have explained what they can.

The ``partial`` statistic (:mod:`stereovar.statistics.registry`) correlates the two
residual fields this module gives: the spline in :math:`\\ln\\mu` alone
(:func:`stereovar.controls.intensity.intensity_residuals`), or with the colour, position and
quantisation terms (:func:`stereovar.controls.covariates.fit_control`) when the caller
passes the pixels' covariates.
"""

from __future__ import annotations

import numpy as np

from ..statistics.robust import log_floor
from .covariates import fit_control
from .intensity import MIN_RESIDUAL_VARIANCE, intensity_residuals


def partial_pair(
    a, b, mu_a, mu_b, *, intervals: int | None = None, covariates=None
) -> tuple[np.ndarray, np.ndarray]:
    """The intensity-controlled pair of one region: each view's residuals.

    .. math::

        \\rho_{\\text{partial}} = \\mathrm{corr}\\bigl(e_L, e_{R\\to L}\\bigr)\\big|_{\\Omega},
        \\qquad e_V = \\ln\\sigma_V^2 - \\hat g_V(\\ln \\mu_V)

    with :math:`\\hat g_V \\approx \\mathrm E[\\ln\\sigma_V^2 \\mid \\ln\\mu_V]` the
    :func:`~stereovar.controls.intensity.intensity_residuals` spline of view :math:`V` on
    the region (its resolution chosen from the view's data,
    :func:`~stereovar.controls.intensity.fit_intensity`), :math:`\\mu` the RGB mean of the
    seed mean and both logarithms floored at the smallest positive value
    (:func:`stereovar.statistics.robust.log_floor`). It is Eq. 3 (paper Sec. 2.3) on what
    intensity does not explain; the control itself is not in the paper. The right-view
    arguments are already warped into the left view (Eq. 2, Sec. 2.2); the registered
    statistic ``partial`` (:mod:`stereovar.statistics.registry`) correlates the pair.

    Parameters
    ----------
    a, b : numpy.ndarray, shape (n,)
        :math:`\\sigma_L^2` and :math:`\\hat\\sigma_{R\\to L}^2` over the region.
    mu_a, mu_b : numpy.ndarray, shape (n,)
        The intensities :math:`\\mu_L` and :math:`\\hat\\mu_{R\\to L}` at the same pixels.
    intervals : int, keyword-only, optional
        Fixed number of knot intervals for both views (default: chosen per view; without
        ``covariates`` only).
    covariates : tuple of two tuples of numpy.ndarray (n,), keyword-only, optional
        Each view's chromaticity (two arrays, or none), the variance its integer encoding
        implies (one array, after the chromaticity, or none) and its position :math:`(x, y)`
        on its own sensor (:func:`stereovar.statistics.fields.control_covariates`): the
        control then removes them too (:func:`stereovar.controls.covariates.fit_control`).

    Returns
    -------
    e_a, e_b : numpy.ndarray, shape (n,)
        The residuals :math:`e_L` and :math:`e_{R\\to L}`.

    Examples
    --------
    Twelve pixels at three intensities, four each. With three distinct values of
    :math:`\\ln\\mu` the conditional mean is each level's mean, so a residual is the log
    variance minus its level's mean. A camera's variance :math:`\\sigma^2 = 0.01\\mu +
    10^{-4}` is a function of :math:`\\mu`: the two views' fields correlate perfectly, yet
    nothing is left once intensity is removed.

    >>> import numpy as np
    >>> mu = np.repeat([0.2, 0.5, 0.9], 4)
    >>> camera = 0.01 * mu + 1e-4
    >>> round(float(np.corrcoef(camera, 2 * camera)[0, 1]), 12)
    1.0
    >>> e_l, e_r = partial_pair(camera, 2 * camera, mu, mu)
    >>> bool(np.isnan(e_l).all() and np.isnan(e_r).all())  # nothing left to correlate
    True

    A Monte Carlo structure :math:`z` with mean 0 at every intensity survives whole
    (:math:`e_L = z`). With :math:`e_R = z + w` and :math:`w \\perp z`,
    :math:`\\rho_{\\text{partial}} = \\lVert z\\rVert / \\lVert z + w\\rVert
    = \\sqrt{0.6 / 0.72} = \\sqrt{5/6}`:

    >>> z = np.tile([0.3, -0.3, 0.1, -0.1], 3)
    >>> w = np.tile([0.1, 0.1, -0.1, -0.1], 3)
    >>> e_l, e_r = partial_pair(0.01 * mu * np.exp(z), 0.03 * mu * np.exp(z + w), mu, mu)
    >>> bool(np.allclose(e_l, z) and np.allclose(e_r, z + w))
    True
    >>> bool(np.isclose(np.corrcoef(e_l, e_r)[0, 1], np.sqrt(5 / 6)))
    True
    """
    la, _ = log_floor(a)
    lb, _ = log_floor(b)
    lma, _ = log_floor(mu_a)
    lmb, _ = log_floor(mu_b)
    if covariates is not None and intervals is None:
        out = []
        for y, x, side in ((la, lma, covariates[0]), (lb, lmb, covariates[1])):
            rest = side[:-2]  # chromaticity (2), then the quantisation variance, if given
            colour = tuple(rest[:2]) if len(rest) >= 2 else None
            quantisation = rest[2] if len(rest) == 3 else None
            out.append(fit_control(y, x, colour=colour, position=tuple(side[-2:]),
                                   quantisation=quantisation).residuals)
    else:
        out = [intensity_residuals(la, lma, intervals=intervals),
               intensity_residuals(lb, lmb, intervals=intervals)]
    if any(np.nanvar(e) < MIN_RESIDUAL_VARIANCE for e in out if np.isfinite(e).any()):
        return np.full(np.shape(a), np.nan), np.full(np.shape(b), np.nan)
    return out[0], out[1]
