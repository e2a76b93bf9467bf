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
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SensorModel:
    """``controls.sensor``: conversion ``gain`` (e- per radiance unit), ``read_noise`` (e-),
    and the ``seed`` of the simulated frames."""

    gain: float = 1000.0
    read_noise: float = 2.0
    seed: int = 0

    def __post_init__(self):
        if not self.gain > 0 or not self.read_noise >= 0:
            raise ValueError(
                f"controls.sensor needs gain > 0 and read_noise >= 0, got gain {self.gain}, "
                f"read_noise {self.read_noise}"
            )


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

    Frame :math:`k` is :math:`(P + R)/g` with :math:`P \\sim \\mathrm{Poisson}(g\\mu)` and
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
        counts = rng.poisson(self._electrons).astype(np.float32)
        counts += rng.normal(0.0, float(self.model.read_noise), size=counts.shape).astype(
            np.float32
        )
        return counts / np.float32(self.model.gain)


def simulated_sensor_variance(mu, n: int, model: SensorModel, seed) -> np.ndarray:
    """Eq. 1 over ``n`` simulated sensor frames of one view (:class:`SensorFrames`).

    .. math::

        \\hat\\sigma^2_{\\text{sensor}}(x, y) = \\frac13 \\sum_c \\frac1N \\sum_{k=1}^{N}
            \\bigl(I_c^{(k)}(x, y) - \\bar I_c(x, y)\\bigr)^2

    computed by :class:`~stereovar.estimators.seeds.StreamingVariance`, the same estimator as
    the renders'. Returns float64 (H, W).
    """
    from ..estimators.seeds import StreamingVariance

    acc = StreamingVariance()
    for frame in SensorFrames(mu, n, model, seed):
        acc.update(frame)
    return acc.variance
