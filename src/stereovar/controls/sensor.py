"""A Poisson-Gaussian camera on the clean image: the sensor-noise baseline.

A real camera's noise variance follows its signal. For a photon-counting sensor with
conversion gain :math:`g` (electrons per unit of scene radiance at the stated exposure) and
read noise :math:`r` electrons, a pixel with clean value :math:`\\mu` records

.. math::

    I = \\frac{P + R}{g}, \\quad P \\sim \\mathrm{Poisson}(g\\mu), \\quad
    R \\sim \\mathcal N(0, r^2), \\qquad
    \\operatorname{Var}[I] = \\frac{\\mu}{g} + \\frac{r^2}{g^2} = a\\mu + b.

Defaults (``controls.sensor``): :math:`g = 1000` e-/unit, :math:`r = 2` e-. They describe a
typical CMOS pixel (full well about 10 000 e-, read noise 1.5-3 e-) exposed so that a clean
value :math:`\\mu = 1` (a white diffuse surface under the scene's key light, in the renderer's
linear radiance units) collects 1000 electrons, a tenth of the full well. Then a = 1e-3 and
b = 4e-6: shot noise dominates wherever :math:`\\mu > 4\\cdot 10^{-3}`. Set ``gain`` low
and ``read_noise`` high for a read-noise-limited (dark, fast-exposure) camera.

The two views' noise streams are independent; only :math:`\\mu` is shared. The clean value
is the per-channel seed mean of the renders (:mod:`stereovar.estimators.seeds`).

Photon counts are drawn exactly up to :data:`POISSON_EXACT_MAX` electrons and from
:math:`\\mathcal N(\\lambda, \\lambda)` above it (:func:`photon_counts`), so a firefly or a
very bright pixel gets its shot noise instead of stopping the run.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

GAIN_RANGE = (1e-3, 1e7)
"""Bounds of ``controls.sensor.gain`` (e- per radiance unit) in the config schema.

From a camera that collects one electron at :math:`\\mu = 1000` (read noise alone below
that) to ten times the largest full well of a real pixel (about :math:`10^6` e-) at
:math:`\\mu = 1`. Within them and :data:`READ_NOISE_MAX`, the read-noise floor
:math:`r/g \\le 10^6` and the variance law :math:`a\\mu + b` stay far inside float32 and
float64, so no camera frame or equalised render overflows."""

READ_NOISE_MAX = 1e3
"""Upper bound of ``controls.sensor.read_noise`` (e-) in the config schema: fifty times a slow
CCD's (3-20 e-; CMOS 1-3 e-)."""


@dataclass(frozen=True)
class SensorModel:
    """``controls.sensor``: conversion ``gain`` (e- per radiance unit), ``read_noise`` (e-),
    and the ``seed`` of the simulated frames."""

    gain: float = 1000.0
    read_noise: float = 2.0
    seed: int = 0

    def __post_init__(self):
        if not 0 < self.gain < np.inf or not 0 <= self.read_noise < np.inf:
            raise ValueError(
                f"controls.sensor needs a finite gain > 0 and read_noise >= 0, got gain "
                f"{self.gain}, read_noise {self.read_noise}"
            )


POISSON_EXACT_MAX = 1e12
"""Largest mean (electrons) whose photon count is drawn from the exact Poisson law.

Above it the count is drawn from :math:`\\mathcal N(\\lambda, \\lambda)`. The two laws' CDFs
differ there by less than :math:`0.5/\\sqrt\\lambda = 5\\cdot 10^{-7}` (Berry-Esseen), the
integer steps of the Poisson law are invisible in the float32 frames (their spacing at
:math:`10^{12}` is :math:`6\\cdot 10^4` electrons), and numpy's exact sampler refuses means above
about :math:`9.2\\cdot 10^{18}` (``lam value too large``), which a pixel of radiance
:math:`10^{16}` reaches at the default gain. Below it the draws are the exact law's."""


def photon_counts(electrons, rng: np.random.Generator):
    """Photon counts of mean ``electrons``: :math:`\\mathrm{Poisson}(\\lambda)` up to
    :data:`POISSON_EXACT_MAX`, :math:`\\mathcal N(\\lambda, \\lambda)` above.

    Only the exact draws are made here, in one call, so an image without large means draws
    exactly what ``rng.poisson(electrons)`` draws.

    Parameters
    ----------
    electrons : numpy.ndarray
        :math:`\\lambda \\ge 0`, float64.
    rng : numpy.random.Generator

    Returns
    -------
    counts : numpy.ndarray, int64, the shape of ``electrons``
        The exact draws; 0 where the mean is large.
    large : numpy.ndarray of bool, or None
        Where the mean is above :data:`POISSON_EXACT_MAX` or not finite (their counts come
        from :func:`normal_counts`, drawn after the caller's other draws); None where none is.

    Examples
    --------
    >>> counts, large = photon_counts(np.array([4.0, 1e20]), np.random.default_rng(0))
    >>> int(counts[1]), large.tolist()
    (0, [False, True])
    """
    electrons = np.asarray(electrons, dtype=np.float64)
    large = ~(electrons <= POISSON_EXACT_MAX)
    if not large.any():
        return rng.poisson(electrons), None
    return rng.poisson(np.where(large, 0.0, electrons)), large


def normal_counts(electrons, large, rng: np.random.Generator) -> np.ndarray:
    """The :math:`\\mathcal N(\\lambda, \\lambda)` counts of the ``large`` entries of
    ``electrons`` (:func:`photon_counts`).

    Parameters
    ----------
    electrons : numpy.ndarray
        :math:`\\lambda \\ge 0`, the mean counts of the whole image.
    large : numpy.ndarray of bool, the shape of ``electrons``
        The entries drawn here (:func:`photon_counts`' second value).
    rng : numpy.random.Generator
        One standard normal draw per large entry, in C order.

    Returns
    -------
    numpy.ndarray, float64, shape (n,)
        :math:`\\lambda + \\sqrt{\\lambda}\\,z` for the ``n`` large entries in C order; NaN or
        Inf where the mean is.
    """
    lam = np.asarray(electrons, dtype=np.float64)[large]
    with np.errstate(invalid="ignore", over="ignore"):
        return lam + np.sqrt(lam) * rng.standard_normal(lam.shape)


def floored_intensity(mu) -> tuple[np.ndarray, int]:
    """The clean value with zero, negative and non-finite entries floored at 0, and how many
    (pixel, channel) entries were floored."""
    mu = np.asarray(mu, dtype=np.float64)
    bad = ~(mu > 0)
    return np.where(bad, 0.0, mu), int(bad.sum() - (mu == 0).sum())


def sensor_variance(mu, model: SensorModel) -> tuple[np.ndarray, int]:
    """The analytic sensor variance field, averaged over channels like Eq. 1.

    .. math::

        \\sigma^2_{\\text{sensor}}(x, y) = \\frac13 \\sum_c
            \\Bigl(\\frac{\\mu_c(x, y)}{g} + \\frac{r^2}{g^2}\\Bigr)

    Parameters
    ----------
    mu : numpy.ndarray, shape (H, W, C)
        Clean per-channel value (the seed mean); zero or negative values are floored at 0.
    model : SensorModel

    Returns
    -------
    variance : numpy.ndarray, float64 (H, W)
    n_floored : int
        (pixel, channel) entries of ``mu`` below zero or non-finite, floored to 0.
    """
    clean, n_floored = floored_intensity(mu)
    g = float(model.gain)
    return clean.mean(axis=-1) / g + (float(model.read_noise) / g) ** 2, n_floored


class SensorFrames(Sequence):
    """``n`` simulated frames of one view, each drawn on access from its own seed.

    Frame :math:`k` is :math:`(P + R)/g` with :math:`P \\sim \\mathrm{Poisson}(g\\mu)` (its
    normal approximation above :data:`POISSON_EXACT_MAX` electrons, :func:`photon_counts`) and
    :math:`R \\sim \\mathcal N(0, r^2)` drawn from ``numpy.random.default_rng((seed, k))``,
    so the sequence can be iterated twice (as the intervention does) and always gives the
    same frames, while holding only :math:`\\mu` in memory.

    Parameters
    ----------
    mu : numpy.ndarray, shape (H, W, C)
        Clean value; zero or negative values are floored at 0.
    n : int
        Number of frames.
    model : SensorModel
    seed : int or sequence of int
        Seed of this view's stream (views must differ).
    """

    def __init__(self, mu, n: int, model: SensorModel, seed):
        self.mu, self.n_floored = floored_intensity(mu)
        with np.errstate(over="ignore"):  # Inf electrons give a non-finite frame entry
            self._electrons = self.mu * float(model.gain)
        self.n = int(n)
        self.model = model
        self.seed = tuple(np.atleast_1d(seed).tolist())

    def __len__(self) -> int:
        return self.n

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(self.n))]
        if not -self.n <= k < self.n:
            raise IndexError(k)
        k %= self.n
        rng = np.random.default_rng((*self.seed, k))
        exact, large = photon_counts(self._electrons, rng)
        counts = exact.astype(np.float32)
        counts += rng.normal(0.0, float(self.model.read_noise), size=counts.shape).astype(
            np.float32
        )
        if large is None:
            return counts / np.float32(self.model.gain)
        shot = normal_counts(self._electrons, large, rng)
        frame = counts / np.float32(self.model.gain)
        with np.errstate(invalid="ignore", over="ignore"):
            frame[large] = (shot + counts[large]) / float(self.model.gain)
        return frame


def eq1_moments(mu, n: int, model: SensorModel) -> tuple[np.ndarray, np.ndarray]:
    """Mean and variance of Eq. 1 over ``n`` Poisson-Gaussian frames, per pixel and channel.

    In electrons, with :math:`\\lambda = g\\mu`, the frame noise has variance
    :math:`\\sigma^2 = \\lambda + r^2` and fourth central moment
    :math:`m_4 = \\lambda + 3\\lambda^2 + 6\\lambda r^2 + 3 r^4`. The population variance
    :math:`s^2 = \\frac{N-1}{N} S^2` of :math:`N` frames then has (Cramér 1946, for the
    unbiased :math:`S^2`)

    .. math::

        \\mathrm E[s^2] = \\frac{N-1}{N}\\sigma^2, \\qquad
        \\operatorname{Var}[s^2] = \\Bigl(\\frac{N-1}{N}\\Bigr)^2
            \\Bigl(\\frac{m_4}{N} - \\frac{\\sigma^4 (N-3)}{N (N-1)}\\Bigr),

    divided by :math:`g^2` and :math:`g^4` for radiance units.

    Returns
    -------
    mean, variance : numpy.ndarray, float64, the shape of ``mu``
    """
    clean, _ = floored_intensity(mu)
    n = int(n)
    if n < 2:
        raise ValueError(f"Eq. 1 needs at least 2 frames, got {n}")
    g, r2 = float(model.gain), float(model.read_noise) ** 2
    scale = (n - 1) / n
    # Var[s^2] as a quadratic in lambda: c2 lambda^2 + c1 lambda + c0 (Horner, in place)
    a, b = 1.0 / n, (n - 3) / (n * (n - 1))
    c2, c1, c0 = 3 * a - b, a * (1 + 6 * r2) - 2 * b * r2, (3 * a - b) * r2 * r2
    unit = scale**2 / g**4
    variance = clean * (g * c2 * unit)
    variance += c1 * unit
    variance *= clean * g
    variance += c0 * unit
    mean = clean * (scale / g)
    mean += scale * r2 / g**2
    return mean, np.maximum(variance, 0.0, out=variance)


def simulated_sensor_variance(mu, n: int, model: SensorModel, seed) -> np.ndarray:
    """Eq. 1 over ``n`` Poisson-Gaussian frames of one view, drawn in one step per pixel.

    Drawing :math:`N` full frames per view costs :math:`N` Poisson samples per pixel and
    channel (seconds per view at 1280x720, N = 30); the Eq. 1 estimate they lead to is drawn
    instead from a gamma distribution with its exact mean and variance
    (:func:`eq1_moments`; the sample variance of Gaussian frames is exactly gamma, and the
    moments carry the Poisson excess kurtosis), then averaged over channels like Eq. 1:

    .. math::

        \\hat\\sigma^2_{\\text{sensor}}(x, y) = \\frac13 \\sum_c s_c^2(x, y), \\qquad
        s_c^2 \\sim \\Gamma\\Bigl(k = \\frac{\\mathrm E[s^2]^2}{\\operatorname{Var}[s^2]},\\
            \\theta = \\frac{\\operatorname{Var}[s^2]}{\\mathrm E[s^2]}\\Bigr).

    The frames themselves (:class:`SensorFrames`, the same law) feed the Sec. 3.4
    intervention; ``tests/test_controls.py`` checks both against each other.

    Returns
    -------
    numpy.ndarray, float64 (H, W)
    """
    mean, variance = eq1_moments(mu, n, model)
    rng = np.random.default_rng(tuple(np.atleast_1d(seed).tolist()))
    with np.errstate(divide="ignore", invalid="ignore"):
        theta = variance / mean
        shape = mean / theta
    if not variance.min() > 0:  # no read noise and mu = 0: s^2 is 0 there
        zero = ~(variance > 0)
        theta[zero], shape[zero] = 0.0, 1.0
    draws = rng.standard_gamma(shape)
    draws *= theta
    return draws.mean(axis=-1)
