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

    returning :math:`\\hat e` (the intensity control, not in the paper; :func:`partial_pair`
    correlates the two views' residuals by Eq. 3, paper Sec. 2.3). A cubic is smooth and follows
    the curvature a Poisson-Gaussian law :math:`\\sigma^2 = a\\mu + b` has in log-log
    coordinates (slope 0 in the read-noise floor, 1 in the shot-noise regime) and the different
    slopes of diffuse and specular pixels, without the step artefacts of a monotone (isotonic)
    fit, which also could not follow a non-monotone relation. The fit solves the normal
    equations of the powers of :math:`\\ln\\mu` mapped onto :math:`[-1, 1]` (the mapping of
    ``numpy.polynomial.Polynomial.fit``, which keeps the 4x4 system well conditioned).

    Parameters
    ----------
    log_variance, log_intensity : numpy.ndarray, shape (n,)
        Finite values of one view over one region.
    degree : int, keyword-only

    Returns
    -------
    numpy.ndarray, shape (n,)
        NaN when fewer than ``degree + 2`` pixels are given.

    Examples
    --------
    A log variance that is a cubic in :math:`\\ln\\mu` is explained entirely:

    >>> import numpy as np
    >>> log_mu = np.linspace(-2.0, 2.0, 9)
    >>> e = intensity_residuals(0.5 + log_mu - 0.25 * log_mu**3, log_mu)
    >>> bool(np.allclose(e, 0.0))
    True
    """
    y = np.asarray(log_variance, dtype=np.float64)
    x = np.asarray(log_intensity, dtype=np.float64)
    if y.size < degree + 2:
        return np.full(y.shape, np.nan)
    design = _scaled_powers(x, degree)
    degree = design.shape[0] - 1
    if degree < 1:
        return y - y.mean()
    # normal equations of the scaled powers: (K+1) passes, not a QR of an (n, K+1) matrix
    gram = np.einsum("in,jn->ij", design, design)
    beta = np.linalg.solve(gram, np.einsum("in,n->i", design, y))
    residual = y - beta[0]
    for k in range(1, degree + 1):
        residual -= beta[k] * design[k]
    return residual


def _scaled_powers(x, degree: int) -> np.ndarray:
    """Rows :math:`u^0, \\ldots, u^K` of :math:`u = (x - c)/h \\in [-1, 1]`, with
    :math:`K` lowered to the number of distinct values minus one."""
    low, high = float(x.min()), float(x.max())
    distinct = np.unique(x[:1024]).size  # enough distinct values in a prefix: done
    rest = x
    if distinct <= degree:
        distinct = 0
        while rest.size and distinct <= degree:
            rest = rest[rest != rest[0]]
            distinct += 1
    degree = min(degree, distinct - 1)
    centre, half = (high + low) / 2.0, (high - low) / 2.0 or 1.0
    design = np.empty((degree + 1, x.size))
    design[0] = 1.0
    if degree >= 1:
        np.subtract(x, centre, out=design[1])
        design[1] *= 1.0 / half
    for k in range(2, degree + 1):
        np.multiply(design[k - 1], design[1], out=design[k])
    return design


def partial_pair(a, b, mu_a, mu_b, *, degree: int = DEGREE) -> tuple[np.ndarray, np.ndarray]:
    """The intensity-controlled pair of one region: each view's residuals.

    .. math::

        \\rho_{\\text{partial}} = \\mathrm{corr}\\bigl(e_L, e_{R\\to L}\\bigr)\\big|_{\\Omega},
        \\qquad e_V = \\ln\\sigma_V^2 - \\hat g_V(\\ln \\mu_V)

    with :math:`\\hat g_V` the :func:`intensity_residuals` fit of view :math:`V` on the
    region, :math:`\\mu` the RGB mean of the seed mean and both logarithms floored at the
    smallest positive value (:func:`stereovar.statistics.robust.log_floor`). It is Eq. 3
    (paper Sec. 2.3) on what intensity does not explain; the control itself is not in the
    paper. The right-view arguments are already warped into the left view (Eq. 2,
    Sec. 2.2); the registered statistic ``partial``
    (:mod:`stereovar.statistics.registry`) correlates the pair.

    Parameters
    ----------
    a, b : numpy.ndarray, shape (n,)
        :math:`\\sigma_L^2` and :math:`\\hat\\sigma_{R\\to L}^2` over the region.
    mu_a, mu_b : numpy.ndarray, shape (n,)
        The intensities :math:`\\mu_L` and :math:`\\hat\\mu_{R\\to L}` at the same pixels.
    degree : int, keyword-only

    Returns
    -------
    e_a, e_b : numpy.ndarray, shape (n,)
        The residuals :math:`e_L` and :math:`e_{R\\to L}`.

    Examples
    --------
    Twelve pixels at three intensities, four each. With three distinct values of
    :math:`\\ln\\mu` the fit is a quadratic through the three level means, so a residual is
    the log variance minus its level's mean. A camera's variance
    :math:`\\sigma^2 = 0.01\\mu + 10^{-4}` is a function of :math:`\\mu`: the two views'
    fields correlate perfectly, yet nothing is left once intensity is removed.

    >>> import numpy as np
    >>> mu = np.repeat([0.2, 0.5, 0.9], 4)
    >>> camera = 0.01 * mu + 1e-4
    >>> round(float(np.corrcoef(camera, 2 * camera)[0, 1]), 12)
    1.0
    >>> e_l, e_r = partial_pair(camera, 2 * camera, mu, mu)
    >>> bool(np.allclose(e_l, 0.0) and np.allclose(e_r, 0.0))
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
