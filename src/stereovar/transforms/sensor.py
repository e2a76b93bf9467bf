"""Camera-noise mitigations: ``sensor_only``, ``equalise`` and ``denoise_sensor``.

All three use the controls' Poisson-Gaussian camera (:mod:`stereovar.controls.sensor`):
conversion gain :math:`g` (e- per radiance unit) and read noise :math:`r` (e-), so a clean
value :math:`\\mu` records a value of variance

.. math::

    \\operatorname{Var}[I] = a\\mu + b, \\qquad a = \\frac1g, \\quad b = \\frac{r^2}{g^2}.

Defaults are the controls' (:class:`~stereovar.controls.sensor.SensorModel`: :math:`g = 1000`,
:math:`r = 2`, a typical CMOS pixel that collects 1000 e- at :math:`\\mu = 1`), so the
``sensor_only`` floor of the mitigation table is the same camera as the sensor control of
Table 1.

Non-finite inputs: a (pixel, channel) entry whose render, seed mean or seed variance is NaN or
Inf is NaN in the output, so the stores' finite flags drop it as they would without the
transform. A non-finite output from finite inputs (a camera past the schema's bounds on
``controls.sensor``, :data:`~stereovar.controls.sensor.GAIN_RANGE`) is refused in one line
naming the transform and the camera (:func:`check_finite`).
"""

from __future__ import annotations

import numpy as np

from ..controls.sensor import (
    GAIN_RANGE,
    READ_NOISE_MAX,
    SensorFrames,
    SensorModel,
    floored_intensity,
)
from ..errors import ConfigError
from .base import TransformInputs
from .denoise import apply_denoise

FLOAT32_MAX = float(np.finfo(np.float32).max)
"""The largest float32: an input past it overflows the float32 output."""

DEFAULT_GAIN = SensorModel.gain
DEFAULT_READ_NOISE = SensorModel.read_noise


def camera_coefficients(*, gain: float = DEFAULT_GAIN, read_noise: float = DEFAULT_READ_NOISE):
    """The camera's variance law :math:`a\\mu + b` as ``(a, b)``.

    .. math:: a = \\frac1g, \\qquad b = \\Bigl(\\frac rg\\Bigr)^2

    Raises
    ------
    ValueError
        ``gain`` is not positive or ``read_noise`` is negative.
    """
    model = SensorModel(gain=float(gain), read_noise=float(read_noise))
    with np.errstate(over="ignore"):  # Inf for a camera past the bounds: check_finite says so
        b = (np.float64(model.read_noise) / model.gain) ** 2
    return 1.0 / model.gain, float(b)


def check_finite(out, expected, *, name: str, gain: float, read_noise: float, source) -> None:
    """Refuse non-finite output where the input is finite.

    Parameters
    ----------
    out : numpy.ndarray
        What the camera model or transform gives.
    expected : numpy.ndarray of bool, the shape of ``out``
        Where the input is finite, so the output must be.
    name : str, keyword-only
        The transform (``"transform 'equalise'"``), for the message.
    gain, read_noise : float, keyword-only
        The camera.
    source : numpy.ndarray, keyword-only
        The finite input (its largest magnitude goes in the message).

    Raises
    ------
    ConfigError
        One line: the transform, the camera, how many values and what to keep within its
        bounds: the gain, the read noise or the input, whichever is past them (all three
        when none is).
    """
    bad = expected & ~np.isfinite(out)
    n = int(bad.sum())
    if not n:
        return
    largest = float(np.abs(np.asarray(source, dtype=np.float64)[expected]).max())
    checks = [
        (
            GAIN_RANGE[0] <= float(gain) <= GAIN_RANGE[1],
            f"controls.sensor.gain within [{GAIN_RANGE[0]:g}, {GAIN_RANGE[1]:g}]",
        ),
        (
            0 <= float(read_noise) <= READ_NOISE_MAX,
            f"controls.sensor.read_noise within [0, {READ_NOISE_MAX:g}]",
        ),
        (
            largest <= FLOAT32_MAX,
            f"the input within float32's range (magnitude at most {FLOAT32_MAX:g})",
        ),
    ]
    keep = [text for ok, text in checks if not ok] or [text for _, text in checks]
    raise ConfigError(
        f"{name} with gain {float(gain):g} e-/unit and read_noise {float(read_noise):g} e- "
        f"gives {n} non-finite value{'s' * (n != 1)} from finite input (largest input "
        f"{largest:g}); keep {_joined(keep)}"
    )


def _joined(words: list) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} and {words[-1]}"


def camera_noise(
    clean,
    *,
    gain: float = DEFAULT_GAIN,
    read_noise: float = DEFAULT_READ_NOISE,
    rng_seed: int,
    name: str = "the camera model",
) -> np.ndarray:
    """One Poisson-Gaussian camera frame of a clean image.

    .. math::

        I = \\frac{P + R}{g}, \\quad P \\sim \\mathrm{Poisson}(g\\,\\max(\\mu, 0)), \\quad
        R \\sim \\mathcal N(0, r^2), \\qquad \\mathrm E[I] = \\mu^+, \\quad
        \\operatorname{Var}[I] = a\\mu^+ + b

    The frame is frame 0 of the controls' :class:`~stereovar.controls.sensor.SensorFrames`
    with seed ``rng_seed`` (its stream is ``numpy.random.default_rng((rng_seed, 0))``), so the
    transforms and the sensor control share one law and one implementation.

    Parameters
    ----------
    clean : numpy.ndarray, shape (H, W, C)
        Clean value :math:`\\mu`; negative entries are floored at 0, non-finite ones give NaN.
    gain, read_noise : float, keyword-only
        :math:`g` and :math:`r`.
    rng_seed : int, keyword-only
    name : str, keyword-only
        Who asks, for the error message (``"transform 'sensor_only'"``).

    Returns
    -------
    numpy.ndarray, float32, the shape of ``clean``

    Raises
    ------
    ConfigError
        A finite clean value gives a non-finite frame value (:func:`check_finite`).
    """
    clean = np.asarray(clean, dtype=np.float64)
    model = SensorModel(gain=float(gain), read_noise=float(read_noise), seed=int(rng_seed))
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        frame = SensorFrames(clean, 1, model, seed=int(rng_seed))[0]
    finite = np.isfinite(clean)
    check_finite(frame, finite, name=name, gain=gain, read_noise=read_noise, source=clean)
    frame[~finite] = np.nan
    return frame.astype(np.float32, copy=False)


def apply_sensor_only(
    inputs: TransformInputs,
    *,
    gain: float = DEFAULT_GAIN,
    read_noise: float = DEFAULT_READ_NOISE,
) -> np.ndarray:
    """``sensor_only``: the converged clean image plus simulated camera noise.

    .. math::

        I'^{(n)} = \\frac{P + R}{g}, \\quad P \\sim \\mathrm{Poisson}(g\\,\\bar I^+), \\quad
        R \\sim \\mathcal N(0, r^2), \\qquad
        \\operatorname{Var}[I'^{(n)}] = a\\bar I^+ + b,

    with :math:`\\bar I^+` the seed mean (Eq. 1's :math:`\\bar I_V`, Sec. 2.1) floored at 0,
    drawn by :func:`camera_noise` from ``inputs.rng_seed``. The render itself is not read: this
    is the floor of the mitigation table, what a real camera would give (Sec. 4: real captures
    carry independent shot- and read-noise streams, :math:`\\rho \\approx 0` after the
    intensity control). TartanAir ships similar random-noise tools for its synthetic images.
    Defaults: the controls' camera (:class:`~stereovar.controls.sensor.SensorModel`).

    Parameters
    ----------
    inputs : TransformInputs
        Needs ``seed_mean``.
    gain, read_noise : float, keyword-only

    Returns
    -------
    numpy.ndarray, float32 (H, W, 3)
    """
    return camera_noise(
        _required(inputs, "seed_mean"),
        gain=gain,
        read_noise=read_noise,
        rng_seed=inputs.rng_seed,
        name="transform 'sensor_only'",
    )


def apply_denoise_sensor(
    inputs: TransformInputs,
    *,
    gain: float = DEFAULT_GAIN,
    read_noise: float = DEFAULT_READ_NOISE,
    clean_aux: bool = False,
    quality: str = "high",
    threads: int = 1,
) -> np.ndarray:
    """``denoise_sensor``: denoise the render, then add camera noise to the result.

    .. math::

        I'^{(n)} = \\frac{P + R}{g}, \\quad
        P \\sim \\mathrm{Poisson}\\bigl(g\\, D(I^{(n)})^+\\bigr), \\quad
        R \\sim \\mathcal N(0, r^2),

    with :math:`D` the ``denoise`` transform
    (:func:`~stereovar.transforms.denoise.apply_denoise`, OIDN as BlenderProc runs it) and the
    camera of :func:`camera_noise`. What a data team does to make synthetic data look like a
    camera. Defaults: the controls' camera
    (:class:`~stereovar.controls.sensor.SensorModel`; Brooks et al. 2019's "unprocessing"
    noise levels are the other common choice, not implemented here) and
    :func:`~stereovar.transforms.denoise.apply_denoise`'s options.

    Returns
    -------
    numpy.ndarray, float32 (H, W, 3)
        NaN where the render is non-finite.
    """
    denoised = apply_denoise(inputs, clean_aux=clean_aux, quality=quality, threads=threads)
    return camera_noise(
        denoised,
        gain=gain,
        read_noise=read_noise,
        rng_seed=inputs.rng_seed,
        name="transform 'denoise_sensor'",
    )


def equalise_residual(
    render,
    seed_mean,
    seed_var,
    *,
    gain: float = DEFAULT_GAIN,
    read_noise: float = DEFAULT_READ_NOISE,
) -> tuple[np.ndarray, int]:
    """Rescale a render's residual from the seed mean to the camera's variance.

    Per pixel and channel, with :math:`\\epsilon = I - \\bar I` (the paper's decomposition
    :math:`I^{(n)} = \\bar I + \\epsilon^{(n)}`, Sec. 3.4) and :math:`\\hat\\sigma^2` the
    unbiased seed variance (Eq. 1 per channel, ``ddof=1``),

    .. math::

        \\epsilon' = \\epsilon \\sqrt{\\frac{a\\bar I^+ + b}{\\hat\\sigma^2}}, \\qquad
        I' = \\bar I + \\epsilon', \\qquad
        \\frac1{N-1} \\sum_n \\bigl(I'^{(n)} - \\bar I\\bigr)^2 = a\\bar I^+ + b

    exactly over the :math:`N` renders the statistics came from: the factor is the same for
    every seed, so the seed mean is unchanged and Eq. 1's variance becomes the camera's
    :math:`a\\mu + b` (:math:`\\bar I^+` the seed mean floored at 0) while each residual keeps
    its shape (sign, spatial pattern, heavy tails).

    Where :math:`\\hat\\sigma^2 = 0` every seed has the same value, :math:`\\epsilon = 0`, and
    there is nothing to rescale: the output is :math:`\\bar I` there (variance 0, not
    :math:`a\\mu + b`; such entries are counted). Where the render, :math:`\\bar I` or
    :math:`\\hat\\sigma^2` is non-finite (or :math:`\\hat\\sigma^2 < 0`) the output is NaN.

    Parameters
    ----------
    render : numpy.ndarray, shape (H, W, C)
    seed_mean, seed_var : numpy.ndarray, shape (H, W, C)
    gain, read_noise : float, keyword-only
        The camera (:func:`camera_coefficients`).

    Returns
    -------
    equalised : numpy.ndarray, float32, the shape of ``render``
    n_zero_variance : int
        Finite (pixel, channel) entries with :math:`\\hat\\sigma^2 = 0`, left at :math:`\\bar I`.

    Raises
    ------
    ConfigError
        Finite inputs give a non-finite output (:func:`check_finite`).
    """
    a, b = camera_coefficients(gain=gain, read_noise=read_noise)
    render = np.asarray(render, dtype=np.float64)
    mean = np.asarray(seed_mean, dtype=np.float64)
    var = np.asarray(seed_var, dtype=np.float64)
    if not render.shape == mean.shape == var.shape:
        raise ValueError(
            f"shapes differ: render {render.shape}, seed_mean {mean.shape}, seed_var {var.shape}"
        )
    good = np.isfinite(render) & np.isfinite(mean) & np.isfinite(var) & (var >= 0)
    zero = good & (var == 0)
    target, _ = floored_intensity(mean)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        target *= a
        target += b
        scale = np.sqrt(target / var)
        out = render - mean
        out *= np.where(zero, 0.0, scale)
        out += mean
        out = out.astype(np.float32)
    check_finite(
        out,
        good,
        name="transform 'equalise'",
        gain=gain,
        read_noise=read_noise,
        source=np.maximum(np.abs(render), np.abs(mean)),
    )
    out[~good] = np.nan
    return out, int(zero.sum())


def apply_equalise(
    inputs: TransformInputs,
    *,
    gain: float = DEFAULT_GAIN,
    read_noise: float = DEFAULT_READ_NOISE,
) -> np.ndarray:
    """``equalise``: the render with its residual rescaled to the camera's variance.

    .. math::

        I' = \\bar I + (I - \\bar I)\\sqrt{\\frac{a\\bar I^+ + b}{\\hat\\sigma^2}}

    (:func:`equalise_residual`). Removes the Monte Carlo variance structure (Sec. 2.1's
    :math:`\\sigma^2`, whose cross-view alignment is the cue) and keeps the noise's shape; the
    variance equalisation the paper's Sec. 4 proposes as a mitigation. Defaults: the
    controls' camera (:class:`~stereovar.controls.sensor.SensorModel`), so the equalised
    variance is the ``sensor_only`` floor's.

    Parameters
    ----------
    inputs : TransformInputs
        Needs ``seed_mean`` and ``seed_var``.
    gain, read_noise : float, keyword-only

    Returns
    -------
    numpy.ndarray, float32 (H, W, 3)
    """
    out, _ = equalise_residual(
        inputs.render,
        _required(inputs, "seed_mean"),
        _required(inputs, "seed_var"),
        gain=gain,
        read_noise=read_noise,
    )
    return out


def _required(inputs: TransformInputs, name: str) -> np.ndarray:
    value = getattr(inputs, name)
    if value is None:
        raise ValueError(f"this transform needs {name}; the inputs do not give it")
    return value
