"""The intensity control (``partial``) against data whose answer is known.

Three cases, all two views of one synthetic scene aligned pixel for pixel:

* a camera: Eq. 1 over N frames of Gaussian noise of variance a*mu + b, independent between the
  views. Nothing but intensity links the views, so the partial rho must be about 0; a misfit
  of the variance-intensity relation is a function of mu, which both views share, and shows
  up as a positive rho (the cubic control left 0.2-0.5 at ln mu spread 2.5 and N = 64);
* ``equalise``'s output through Eq. 1: its variance is exactly (N-1)/N (a*mu + b), so
  the only noise left is float32 rounding and any misfit reads as a cue (the cubic: 0.6-0.98);
* a planted cue: a smooth log-variance pattern shared by the views, independent of mu, must
  come through at the level the estimation noise of Eq. 1 allows.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage, special
from scipy.interpolate import BSpline

from stereovar.controls import intensity
from stereovar.controls.intensity import fit_intensity, intensity_residuals
from stereovar.controls.partial import partial_pair
from stereovar.estimators.seeds import variance_field
from stereovar.transforms.base import TransformInputs
from stereovar.transforms.sensor import apply_equalise, camera_coefficients

SHAPE = (128, 160)
A, B = camera_coefficients()  # the project's default camera: 1/1000, (2/1000)^2
NULL = 0.05
"""|partial rho| a null may reach: 7 standard errors of rho at 20 480 independent pixels."""


def _smooth(rng, scale: float) -> np.ndarray:
    """A smooth random field of mean 0 and standard deviation 1."""
    field = ndimage.gaussian_filter(rng.normal(size=SHAPE), scale)
    return (field - field.mean()) / field.std()


def _scene(rng, spread: float, *, centre: float = -2.0, uniform: bool = False, tint=0.1):
    """Clean per-channel intensities (H, W, 3) of a left view and the right view at the same
    pixels: ln mu has standard deviation ``spread`` (a Gaussian marginal, or a uniform one of
    the same spread), a small per-channel tint, and the right view differs by a smooth
    view-dependent factor (about 5%)."""
    field = _smooth(rng, 8.0)
    if uniform:
        field = np.sqrt(12.0) * (special.ndtr(field) - 0.5)
    log_mu = centre + spread * field
    colour = tint * np.stack([_smooth(rng, 6.0) for _ in range(3)], axis=-1)
    left = np.exp(log_mu[..., None] + colour)
    right = left * np.exp(0.05 * _smooth(rng, 10.0))[..., None]
    return left, right


def _eq1(frames) -> np.ndarray:
    """Eq. 1, flattened: the RGB-averaged population variance over the frames."""
    return variance_field(frames)[1].reshape(-1)


def _grey(mu) -> np.ndarray:
    """The control's intensity: the RGB mean, flattened."""
    return np.asarray(mu).mean(axis=-1).reshape(-1)


def _mean_zero_at_every_intensity(pattern, mu, bins: int = 64) -> np.ndarray:
    """``pattern`` minus its mean over each of ``bins`` equal-count bins of ln mu: a pattern
    whose conditional mean given intensity is 0, scaled back to its standard deviation."""
    log_mu = np.log(_grey(mu))
    edges = np.quantile(log_mu, np.linspace(0.0, 1.0, bins + 1)[1:-1])
    label = np.searchsorted(edges, log_mu)
    flat = pattern.reshape(-1)
    means = np.bincount(label, flat, bins) / np.bincount(label, minlength=bins)
    out = flat - means[label]
    return (out * (flat.std() / out.std())).reshape(pattern.shape)


def _rho(pair) -> float:
    return float(np.corrcoef(*pair)[0, 1])


def _camera_frames(rng, mu, n: int, a: float, b: float, pattern=None) -> np.ndarray:
    """N frames of Gaussian noise of variance (a mu + b) exp(pattern) per pixel and channel."""
    variance = a * mu + b
    if pattern is not None:
        variance = variance * np.exp(pattern)[..., None]
    return mu + np.sqrt(variance) * rng.normal(size=(n, *mu.shape))


def _true_residual_rho(var_l, var_r, mu_l, mu_r, a, b) -> float:
    """Partial rho with the true conditional mean ln(a mu + b) removed instead of a fit."""
    return _rho((np.log(var_l) - np.log(a * mu_l + b), np.log(var_r) - np.log(a * mu_r + b)))


# ---------------------------------------------------------------- the camera: about 0


@pytest.mark.parametrize("spread", [1.2, 2.5])
@pytest.mark.parametrize("n", [8, 64])
@pytest.mark.parametrize("gain", [1000.0, 100.0])
def test_camera_law_leaves_no_partial_rho(spread, n, gain):
    """Eq. 1 of a camera's frames: partial rho about 0, as with the true law removed.

    The intensities are the clean fields the noise law is a function of (a gain of 100 is
    a = 1/100: noise visible in the frames)."""
    a, b = camera_coefficients(gain=gain)
    rng = np.random.default_rng([7, int(10 * spread), n, int(gain)])
    mu_l, mu_r = _scene(rng, spread)
    var_l = _eq1(_camera_frames(rng, mu_l, n, a, b))
    var_r = _eq1(_camera_frames(rng, mu_r, n, a, b))
    grey_l, grey_r = _grey(mu_l), _grey(mu_r)
    assert abs(_true_residual_rho(var_l, var_r, grey_l, grey_r, a, b)) < NULL  # a null
    assert abs(_rho(partial_pair(var_l, var_r, grey_l, grey_r))) < NULL


def test_camera_law_with_the_frames_own_seed_mean():
    """As the statistic runs: the intensity is the frames' seed mean, noisy itself."""
    rng = np.random.default_rng(11)
    mu_l, mu_r = _scene(rng, 2.5)
    (mean_l, var_l), (mean_r, var_r) = (
        variance_field(_camera_frames(rng, mu, 64, A, B)) for mu in (mu_l, mu_r)
    )
    pair = partial_pair(var_l.ravel(), var_r.ravel(), _grey(mean_l), _grey(mean_r))
    assert abs(_rho(pair)) < NULL


# ---------------------------------------------------------------- equalise: about 0


def _equalised_variance(rng, mu, n: int, relative_sd, view: str):
    """Monte Carlo-like renders (gamma noise of mean mu and relative standard deviation
    ``relative_sd`` per pixel) and Eq. 1 over them before and after ``equalise`` (run as
    the mitigation job runs it: seed mean and unbiased seed variance of the same N renders),
    with the seed mean's RGB mean."""
    shape = 1.0 / relative_sd**2
    renders = rng.gamma(np.broadcast_to(shape[..., None], (n, *mu.shape)), 1.0 / shape[..., None])
    renders = (renders * mu).astype(np.float32)
    mean = renders.mean(axis=0, dtype=np.float64)
    var = renders.var(axis=0, ddof=1, dtype=np.float64)
    equalised = np.stack(
        [
            apply_equalise(TransformInputs(r, view, i, i, seed_mean=mean, seed_var=var, n_seeds=n))
            for i, r in enumerate(renders)
        ]
    )
    return _eq1(renders), _eq1(equalised), _grey(mean)


@pytest.mark.parametrize("spread", [1.2, 2.5])
@pytest.mark.parametrize("n", [8, 64])
def test_equalise_output_leaves_no_partial_rho(spread, n):
    """The renders carry a shared relative-variance pattern (a cue the control must keep);
    ``equalise`` sets every pixel's Eq. 1 variance to (N-1)/N (a mu + b) of its own seed mean,
    and the control must not turn its misfit of that law into a cue.

    ln mu has a uniform marginal (a bounded dynamic range, about e^9 at spread 2.5): a
    Gaussian one puts pixels at e^(+-9), where the float32 rounding that is an equalised
    field's only noise is itself structured and even the exact law wanders by 0.08."""
    rng = np.random.default_rng([3, int(10 * spread), n])
    mu_l, mu_r = _scene(rng, spread, uniform=True)
    relative_sd = 0.6 * np.exp(0.4 * _smooth(rng, 5.0))
    raw_l, eq_l, grey_l = _equalised_variance(rng, mu_l, n, relative_sd, "left")
    raw_r, eq_r, grey_r = _equalised_variance(rng, mu_r, n, relative_sd, "right")
    # what equalise promises, so the only cross-view link left is intensity
    np.testing.assert_allclose(eq_l, (n - 1) / n * (A * grey_l + B), rtol=1e-5)
    assert _rho(partial_pair(raw_l, raw_r, grey_l, grey_r)) > 0.3  # the cue is in the renders
    # explained to round-off: nothing left to correlate, so partial is undefined, not a
    # remainder's heavy-tailed rho (tests/test_equalise_coverage.py)
    e_l, e_r = partial_pair(eq_l, eq_r, grey_l, grey_r)
    assert np.isnan(e_l).all() and np.isnan(e_r).all()


# ---------------------------------------------------------------- a planted cue: kept


@pytest.mark.parametrize(("strength", "n"), [(0.3, 8), (0.15, 64), (0.05, 64)])
def test_planted_cue_comes_through(strength, n):
    """ln sigma^2 = ln(a mu + b) + s z + noise, with z a smooth pattern shared by the views and
    of mean 0 at every intensity. For grey pixels Eq. 1 is sigma^2 chi^2_{3(N-1)} / (3N),
    whose logarithm has variance trigamma(3(N-1)/2), so

    .. math:: \\rho = \\frac{s^2}{s^2 + \\psi_1(3(N-1)/2)}

    (z has variance 1). The control must give that, and what the true law gives."""
    rng = np.random.default_rng([5, n, int(100 * strength)])
    mu_l, mu_r = _scene(rng, 2.0, tint=0.0)
    z = _mean_zero_at_every_intensity(strength * _smooth(rng, 4.0), mu_l)
    var_l = _eq1(_camera_frames(rng, mu_l, n, A, B, pattern=z))
    var_r = _eq1(_camera_frames(rng, mu_r, n, A, B, pattern=z))
    grey_l, grey_r = _grey(mu_l), _grey(mu_r)
    expected = strength**2 / (strength**2 + special.polygamma(1, 1.5 * (n - 1)))
    true_law = _true_residual_rho(var_l, var_r, grey_l, grey_r, A, B)
    got = _rho(partial_pair(var_l, var_r, grey_l, grey_r))
    assert true_law == pytest.approx(expected, abs=0.03)
    assert got == pytest.approx(true_law, abs=0.01)
    assert got > 0.15


def test_planted_cue_on_a_small_region_is_not_absorbed():
    """A region of 600 pixels: the spline stays coarse enough to keep the cue."""
    rng = np.random.default_rng(8)
    mu_l, mu_r = _scene(rng, 1.5, tint=0.0)
    keep = np.zeros(SHAPE, bool)
    keep[40:60, 50:80] = True
    z = np.zeros(SHAPE)
    z[keep] = _mean_zero_at_every_intensity(0.3 * _smooth(rng, 4.0)[keep], mu_l[keep], 16)
    var_l = _eq1(_camera_frames(rng, mu_l, 16, A, B, pattern=z))[keep.ravel()]
    var_r = _eq1(_camera_frames(rng, mu_r, 16, A, B, pattern=z))[keep.ravel()]
    grey_l, grey_r = _grey(mu_l)[keep.ravel()], _grey(mu_r)[keep.ravel()]
    true_law = _true_residual_rho(var_l, var_r, grey_l, grey_r, A, B)
    assert _rho(partial_pair(var_l, var_r, grey_l, grey_r)) == pytest.approx(true_law, abs=0.05)


# ---------------------------------------------------------------- the fit itself


def test_fit_is_the_least_squares_spline_on_its_knots():
    """The moments' algebra gives the brute-force least-squares residuals of the same cubic
    B-spline basis (a dense lstsq over every pixel)."""
    rng = np.random.default_rng(2)
    x = rng.normal(-1.5, 1.2, 20_000)
    y = np.log(A * np.exp(x) + B) + 0.1 * rng.normal(size=x.size)
    for k in (1, 4, 32):
        knots = intensity._knots(intensity._bin_moments(x, y), k)
        design = BSpline.design_matrix(x, knots, 3).toarray()
        beta, *_ = np.linalg.lstsq(design, y, rcond=None)
        got = intensity_residuals(y, x, intervals=k)
        np.testing.assert_allclose(got, y - design @ beta, atol=1e-7)


def test_resolution_is_chosen_from_the_data():
    """A noiseless camera law needs many knots; a straight line under noise needs one."""
    x = np.linspace(-8.0, 1.0, 50_000)
    law = np.log(A * np.exp(x) + B)
    fit = fit_intensity(law, x)
    assert fit.intervals >= 64
    assert np.abs(fit.residuals).max() < 1e-6
    rng = np.random.default_rng(4)
    line = fit_intensity(0.7 * x + rng.normal(size=x.size), x)
    assert line.intervals <= 2
    # the fixed resolution is what it says: one interval is a cubic polynomial
    cubic = np.polynomial.Polynomial.fit(x, law, 3)
    np.testing.assert_allclose(intensity_residuals(law, x, intervals=1), law - cubic(x), atol=1e-6)


def test_pixel_order_does_not_matter():
    rng = np.random.default_rng(6)
    x = rng.normal(-2.0, 1.5, 30_000)
    y = np.log(A * np.exp(x) + B) + 0.2 * rng.normal(size=x.size)
    order = rng.permutation(x.size)
    np.testing.assert_allclose(
        intensity_residuals(y[order], x[order]), intensity_residuals(y, x)[order], atol=1e-9
    )


def test_degenerate_inputs():
    """Non-finite pixels give NaN there; fewer than 5 finite pixels, NaN everywhere; one
    intensity, the deviations from the mean."""
    x = np.linspace(-2.0, 0.0, 40)
    y = 0.5 * x + np.sin(7 * x)
    y[3], x[5] = np.nan, np.inf
    e = intensity_residuals(y, x)
    assert np.isnan(e[[3, 5]]).all() and np.isfinite(np.delete(e, [3, 5])).all()
    assert np.isnan(intensity_residuals(np.ones(4), np.arange(4.0))).all()
    y = np.arange(6.0)
    np.testing.assert_allclose(intensity_residuals(y, np.full(6, -1.0)), y - y.mean())
