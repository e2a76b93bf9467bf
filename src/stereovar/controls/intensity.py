"""The intensity control: cross-view variance structure beyond what intensity explains.

A camera's noise variance is a function of the signal (:mod:`stereovar.controls.sensor`), and
both views see the same scene, so any two signal-dependent noise fields correlate once
aligned. Removing each view's variance-intensity relation leaves the part of the cross-view
structure that such a sensor would not have.
"""

from __future__ import annotations

import numpy as np

from ..statistics.robust import log_floor

DEGREE = 3
"""Degree of the polynomial in :math:`\\ln \\mu` fitted to :math:`\\ln \\sigma^2`."""


def intensity_residuals(log_variance, log_intensity, *, degree: int = DEGREE) -> np.ndarray:
    """Residuals of :math:`\\ln\\sigma^2` after a least-squares polynomial in :math:`\\ln\\mu`.

    .. math::

        \\ln \\sigma^2_i = \\sum_{k=0}^{K} \\beta_k (\\ln \\mu_i)^k + e_i, \\qquad
        \\hat\\beta = \\arg\\min_\\beta \\sum_i e_i^2,

    returning :math:`\\hat e`. A cubic is smooth and follows the curvature a
    Poisson-Gaussian law :math:`\\sigma^2 = a\\mu + b` has in log-log coordinates (slope 0 in
    the read-noise floor, 1 in the shot-noise regime) and the different slopes of diffuse and
    specular pixels, without the step artefacts of a monotone (isotonic) fit, which also
    could not follow a non-monotone relation. The fit is solved on a centred and scaled
    :math:`\\ln\\mu` (``numpy.polynomial.Polynomial.fit``) for conditioning.

    Parameters
    ----------
    log_variance, log_intensity : numpy.ndarray, shape (n,)
        Finite values of one view over one region.
    degree : int, keyword-only

    Returns
    -------
    numpy.ndarray, shape (n,)
        NaN when fewer than ``degree + 2`` pixels are given.
    """
    y = np.asarray(log_variance, dtype=np.float64)
    x = np.asarray(log_intensity, dtype=np.float64)
    if y.size < degree + 2:
        return np.full(y.shape, np.nan)
    degree = min(degree, np.unique(x).size - 1)
    if degree < 1:
        return y - y.mean()
    fit = np.polynomial.Polynomial.fit(x, y, degree)
    return y - fit(x)


def partial_pair(a, b, mu_a, mu_b, *, degree: int = DEGREE) -> tuple[np.ndarray, np.ndarray]:
    """The intensity-controlled pair of one region: each view's residuals.

    .. math:: \\rho_{\\text{partial}} = \\mathrm{corr}\\bigl(e_L, e_{R\\to L}\\bigr), \\qquad
        e_V = \\ln\\sigma_V^2 - \\hat g_V(\\ln \\mu_V)

    with :math:`\\hat g_V` the :func:`intensity_residuals` fit of view :math:`V` on the
    region, :math:`\\mu` the RGB mean of the seed mean and both logarithms floored at the
    smallest positive value (:func:`stereovar.statistics.robust.log_floor`).
    """
    la, _ = log_floor(a)
    lb, _ = log_floor(b)
    lma, _ = log_floor(mu_a)
    lmb, _ = log_floor(mu_b)
    return (
        intensity_residuals(la, lma, degree=degree),
        intensity_residuals(lb, lmb, degree=degree),
    )


def relative_variance(variance, intensity) -> np.ndarray:
    """Relative variance :math:`\\sigma^2 / \\mu^2`, which removes albedo; NaN where
    :math:`\\mu \\le 0`.

    .. math:: v_{\\text{rel}}(x, y) = \\frac{\\sigma^2(x, y)}{\\mu(x, y)^2}
    """
    var = np.asarray(variance, dtype=np.float64)
    mu = np.asarray(intensity, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(mu > 0, var / (mu * mu), np.nan)
