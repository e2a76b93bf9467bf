"""Camera pipelines with no Monte Carlo cue that lie outside the basic null's class.

The ``camera`` null (:mod:`stereovar.calibration.synthesis`) draws float, linear noise whose
variance is :math:`a\\mu + b` of each channel, the same at every image position. The data
teams ship rarely looks like that: generators write 8-bit sRGB PNG, cameras and "look like a
camera" pipelines apply white balance, colour matrices and lens-shading correction. Each
pipeline here draws :math:`N` frames per view around a scene's clean images with independent
noise per view (so there is no cross-view cue of any kind), passes them through one such
step, and decodes them as the import would. A control or null that sees only luminance, or a
null drawn in float, calls some of these a cue; the calibration publishes each one's
false-positive rate (``DESIGN.md``, Calibration: pipeline nulls).

``shading``
    lens-shading correction: the raw frames multiplied by a gain that rises from 1 at the
    centre to 4 at the corners (:func:`shading_gain`), both sensors alike;
``gain_map``
    shading and a fixed smooth gain map (about 20% over 24 pixels) shared by both sensors;
``srgb8_<q>``
    8-bit sRGB encoding (rounding, clipping) at :math:`q` digital numbers of noise at mid
    grey: the low-noise images a denoised render ships as (0.2, 0.4 and 1 DN);
``white_balance``
    per-channel gains (2, 1, 1.6) after raw shot noise;
``colour_matrix``
    white balance then a colour-correction matrix (:data:`COLOUR_MATRIX`);
``power_law``
    a non-linear law :math:`a'\\mu_c^{1.6} + b` per channel;
``correlated``
    the camera law with the channels of a pixel correlated 0.9 (a path tracer's are 0.88 to
    0.93).

The 8-bit pipelines' matched null is the camera law through the same encoding
(:func:`encoded_law` sets its level before the encoding); the others are read against the
``camera`` null, and the intensity control's colour and position terms
(:mod:`stereovar.controls.covariates`) must explain them.
"""

from __future__ import annotations

import numpy as np

from .synthesis import draw_frames, smooth_field

WHITE_BALANCE = (2.0, 1.0, 1.6)
"""Per-channel gains of ``white_balance`` and ``colour_matrix`` (a daylight balance of a
Bayer sensor)."""

COLOUR_MATRIX = np.array([[1.6, -0.4, -0.2], [-0.3, 1.5, -0.2], [0.0, -0.5, 1.5]])
"""Camera RGB to output RGB of ``colour_matrix`` (rows sum to 1, so grey stays grey)."""

SHADING_CORNER_GAIN = 4.0
"""The lens-shading correction's gain in the image corners (1 at the centre)."""

GAIN_MAP_SD = 0.2
"""Standard deviation of the fixed gain map's logarithm."""

GAIN_MAP_SCALE = 24.0
"""Smoothing, in pixels, of the fixed gain map."""

POWER = 1.6
"""Exponent of ``power_law``."""

CORRELATION = 0.9
"""The channels' noise correlation of ``correlated``."""

MID_GREY = 0.214
"""Linear value of sRGB 0.5, where an 8-bit pipeline's noise is stated in DN."""

ENCODED_NOISE_DN = (0.2, 0.4, 1.0)
"""Noise at mid grey of the 8-bit pipelines, in digital numbers."""

PIPELINES = (
    "shading",
    "gain_map",
    *(f"srgb8_{q:g}" for q in ENCODED_NOISE_DN),
    "white_balance",
    "colour_matrix",
    "power_law",
    "correlated",
)
"""Every pipeline null, in the order the calibration draws them."""


def encoding_of(pipeline: str) -> str:
    """The encoding a pipeline's frames pass through: ``srgb8`` or ``float``."""
    return "srgb8" if pipeline.startswith("srgb8_") else "float"


def shading_gain(shape) -> np.ndarray:
    """A lens-shading correction's gain over the sensor.

    .. math:: G(x, y) = 1 + (G_c - 1)\\,\\frac{r^2}{r_c^2}

    with :math:`r` the distance from the image centre, :math:`r_c` the corners' and
    :math:`G_c` :data:`SHADING_CORNER_GAIN` (the :math:`\\cos^4` fall-off of a lens,
    corrected).

    Examples
    --------
    >>> g = shading_gain((5, 9))
    >>> float(g[2, 4]), float(g[0, 0])
    (1.0, 4.0)
    """
    h, w = shape[:2]
    y, x = np.indices((h, w), dtype=np.float64)
    r2 = (x - (w - 1) / 2) ** 2 + (y - (h - 1) / 2) ** 2
    return 1.0 + (SHADING_CORNER_GAIN - 1.0) * r2 / r2.max()


def integer_roundtrip(frames, *, bits: int, transfer: str = "srgb", scale: float = 1.0):
    """Frames written as integers of ``bits`` bits and read back as the import reads them
    (:func:`stereovar.io.images.read_image`: the code value over full scale, decoded by the
    transfer curve, times ``scale``), in the units of ``frames``.

    .. math:: I' = s\\,T^{-1}\\Bigl(\\frac{\\operatorname{round}\\bigl((2^B - 1)\\,
        T(\\operatorname{clip}(I/s, 0, 1))\\bigr)}{2^B - 1}\\Bigr)

    with :math:`T` the sRGB curve (``transfer="srgb"``) or the identity (``"linear"``).

    Examples
    --------
    Values between two 8-bit codes go to the nearer; full scale clips:

    >>> import numpy as np
    >>> integer_roundtrip(np.array([0.1, 0.1 + 0.4 / 255, 2.0]), bits=8, transfer="linear")
    array([0.10196079, 0.10196079, 1.        ], dtype=float32)
    """
    from ..io.transfer import linear_to_srgb, srgb_to_linear

    full = float(2 ** int(bits) - 1)
    v = np.clip(np.asarray(frames, dtype=np.float64) / scale, 0.0, 1.0)
    if transfer != "srgb":
        return (np.rint(full * v) / full * scale).astype(np.float32)
    code = np.rint(full * linear_to_srgb(v)).astype(np.intp)
    # decoded once per code value (the same numbers as decoding every pixel's code)
    decoded = srgb_to_linear(np.arange(int(full) + 1) / full) * scale
    return decoded[code].astype(np.float32)


def encoded_frames(frames, encoding: dict | None):
    """``frames`` through the data's integer encoding, when it has one
    (:func:`integer_roundtrip` with ``encoding``'s ``bits``, ``transfer`` and ``scale``;
    ``frames`` unchanged when ``encoding`` is None or empty)."""
    return frames if not encoding else integer_roundtrip(frames, **encoding)


def exposure_for(mean) -> float:
    """The exposure that puts the 99th percentile of a clean image's channel values at 0.9
    of full scale (where a generator's view transform would)."""
    top = float(np.percentile(np.asarray(mean, dtype=np.float64), 99))
    return 0.9 / top if top > 0 else 1.0


def dn_law(law, exposure: float, dn: float) -> tuple[float, float]:
    """The camera law :math:`(a, b)` rescaled so that its noise at mid grey is ``dn``
    digital numbers of 8-bit sRGB at this exposure.

    .. math:: c\\,(a\\,m + b) = \\Bigl(\\frac{q}{255\\,\\mathrm{sRGB}'(m)}\\Bigr)^2 / e^2,
        \\qquad m = \\text{mid grey} / e
    """
    a, b = law
    slope = 1.055 / 2.4 * MID_GREY ** (1 / 2.4 - 1)
    target = (dn / (255.0 * slope)) ** 2 / exposure**2
    level = a * MID_GREY / exposure + b
    c = target / level if level > 0 else 1.0
    return a * c, b * c


def draw_pipeline(name: str, mean: dict, law, n: int, rng: np.random.Generator,
                  gain_map=None) -> dict:
    """:math:`N` frames per view of pipeline ``name`` around the clean images ``mean``.

    Parameters
    ----------
    name : str
        One of :data:`PIPELINES`.
    mean : dict
        View to the clean image (H, W, C), linear.
    law : (a, b)
        The raw camera law (:func:`~stereovar.calibration.synthesis.camera_law`).
    n : int
    rng : numpy.random.Generator
    gain_map : numpy.ndarray (H, W), optional
        ``gain_map``'s fixed map (drawn from ``rng`` when not given; a scene keeps one).

    Returns
    -------
    dict
        View to frames (N, H, W, C), float32, in the clean images' units.
    """
    a, b = law
    out = {}
    shape = next(iter(mean.values())).shape
    gain = None
    if name in ("shading", "gain_map"):
        gain = shading_gain(shape)
        if name == "gain_map":
            if gain_map is None:
                gain_map = np.exp(GAIN_MAP_SD * smooth_field(shape[:2], rng, scale=GAIN_MAP_SCALE))
            gain = gain * gain_map
    exposure = dn = None
    if name.startswith("srgb8_"):
        dn = float(name.split("_", 1)[1])
        exposure = exposure_for(mean["left"])
        a, b = dn_law(law, exposure, dn)
    for view, clean in mean.items():
        clean = np.maximum(np.asarray(clean, dtype=np.float64), 0.0)
        if gain is not None:
            raw = clean / gain[..., None]
            frames = draw_frames(raw, a * raw + b, n, rng) * gain[..., None].astype(np.float32)
        elif name in ("white_balance", "colour_matrix"):
            w = np.asarray(WHITE_BALANCE)
            full = COLOUR_MATRIX @ np.diag(w) if name == "colour_matrix" else np.diag(w)
            raw = clean @ np.linalg.inv(full).T
            raw_var = a * np.maximum(raw, 0.0) + b
            noise = draw_frames(np.zeros_like(raw), raw_var, n, rng)
            frames = (clean[None] + noise @ full.T).astype(np.float32)
        elif name == "power_law":
            centre = float(np.median(clean))
            scale = (a * centre + b) / max(centre**POWER, 1e-12)
            frames = draw_frames(clean, scale * clean**POWER + b, n, rng)
        elif name == "correlated":
            frames = draw_frames(clean, a * clean + b, n, rng, channel_correlation=CORRELATION)
        elif exposure is not None:
            frames = integer_roundtrip(draw_frames(clean, a * clean + b, n, rng), bits=8,
                                       scale=1.0 / exposure)
        else:
            raise ValueError(f"unknown pipeline {name!r}; use one of {', '.join(PIPELINES)}")
        out[view] = frames
    return out


def pipeline_encoding(name: str, mean: dict) -> dict | None:
    """What a pipeline's frames pass through: ``{"bits", "transfer", "scale"}`` of the
    8-bit ones (:func:`integer_roundtrip`'s arguments), None for the float ones."""
    if not name.startswith("srgb8_"):
        return None
    return {"bits": 8, "transfer": "srgb", "scale": 1.0 / exposure_for(mean["left"])}


def _code_slope(v: np.ndarray, transfer: str) -> np.ndarray:
    """:math:`dT/dv` of the transfer curve at :math:`v \\in [0, 1]`."""
    if transfer != "srgb":
        return np.ones_like(v)
    safe = np.maximum(v, 0.0031308)
    return np.where(v <= 0.0031308, 12.92, 1.055 / 2.4 * safe ** (1 / 2.4 - 1))


def dequantised_mean(mean, law, encoding: dict, n: int) -> np.ndarray:
    """The clean image behind the seed mean of :math:`N` integer-coded frames, where the
    noise is below half a code.

    With noise of :math:`\\sigma` codes around a clean value :math:`k + f` (code :math:`k`,
    :math:`0 \\le f < 1`), a frame reads :math:`k + 1` with probability
    :math:`p = \\Phi((f - \\tfrac12)/\\sigma)`, so the share :math:`\\hat p` of frames
    that do, which the seed mean gives in codes, estimates

    .. math:: \\hat f = \\tfrac12 + \\sigma\\,\\Phi^{-1}(\\hat p)

    (:math:`\\hat f = 0` or 1 where every frame read the same code). The seed mean itself
    sits near a code wherever the frames rarely flip, so a null drawn around it flips less
    often than the data did where they did: a matched null drawn around :math:`\\hat f`
    reproduces each pixel's flips, and with them the variance pattern that 8-bit
    quantisation of a low-noise image gives both views alike. Where the noise is half a code
    or more the seed mean is kept.

    Parameters
    ----------
    mean : numpy.ndarray (H, W, C)
        The seed mean of the decoded frames, linear.
    law : (a, b)
        The camera law before the encoding (:func:`encoded_law`).
    encoding : dict
        :func:`integer_roundtrip`'s ``bits``, ``transfer`` and ``scale``.
    n : int
        Frames behind the seed mean.
    """
    from scipy.special import ndtri

    from ..io.transfer import linear_to_srgb, srgb_to_linear

    mean = np.asarray(mean, dtype=np.float64)
    scale, transfer = float(encoding["scale"]), encoding.get("transfer", "srgb")
    full = float(2 ** int(encoding["bits"]) - 1)
    v = np.clip(mean / scale, 0.0, 1.0)
    code = full * (linear_to_srgb(v) if transfer == "srgb" else v)
    a, b = law
    sigma = np.sqrt(np.maximum(a * np.maximum(mean, 0.0) + b, 0.0)) / scale
    sigma = sigma * _code_slope(v, transfer) * full
    k = np.floor(code + 1e-6)
    p = code - k
    tiny = 0.25 / max(int(n), 1)
    f = 0.5 + sigma * ndtri(np.clip(p, tiny, 1 - tiny))
    f = np.where(p < tiny, 0.0, np.where(p > 1 - tiny, 1.0, np.clip(f, 0.0, 1.0)))
    centre = np.clip((k + f) / full, 0.0, 1.0)
    linear = (srgb_to_linear(centre) if transfer == "srgb" else centre) * scale
    return np.where(sigma < 0.5, linear, mean)


def encoded_clean(mean, variance, law, n: int, rng: np.random.Generator, encoding: dict):
    """The camera law before the encoding and the clean image a matched null is drawn around:
    :func:`encoded_law` on the seed mean, then :func:`dequantised_mean` at that law and the
    law again around it.

    Returns
    -------
    law : (a, b)
    clean : numpy.ndarray (H, W, C)
    """
    first = encoded_law(mean, variance, law, n, rng, encoding)
    clean = dequantised_mean(mean, first, encoding, n)
    second = encoded_law(clean, variance, law, n, rng, encoding)
    return second, dequantised_mean(mean, second, encoding, n)


LAW_FACTORS = np.geomspace(1e-3, 10.0, 17)
"""Multipliers of the camera law tried by :func:`encoded_law`."""


def encoded_law(mean, variance, law, n: int, rng: np.random.Generator, encoding: dict,
                factors=LAW_FACTORS) -> tuple[float, float]:
    """The camera law before an encoding: the multiple :math:`c\\,(a, b)` of the law fitted
    to the decoded data whose frames, drawn and encoded as the data were, give the data's
    median Eq. 1 variance.

    .. math:: \\hat c = \\arg\\min_c \\bigl|\\ln \\operatorname{med}\\sigma^2_c -
        \\ln\\operatorname{med}\\sigma^2_{\\text{data}}\\bigr|

    over ``factors`` (interpolated in logarithms), with :math:`\\sigma^2_c` Eq. 1 of
    :math:`N` frames of one view drawn at :math:`c\\,(a\\mu + b)` and encoded
    (:func:`integer_roundtrip`). Quantisation adds variance (and removes it where the noise
    is far below one code), so a law fitted to the decoded data is not the law before the
    encoding; a matched null drawn at it and then encoded would not reproduce the data.

    Parameters
    ----------
    mean, variance : numpy.ndarray (H, W, C), (H, W)
        One view's seed mean and Eq. 1 field.
    law : (a, b)
    encoding : dict
        :func:`integer_roundtrip`'s ``bits``, ``transfer`` and ``scale``.

    Returns
    -------
    a, b : float
    """
    clean = np.maximum(np.asarray(mean, dtype=np.float64), 0.0)
    target = float(np.nanmean(np.asarray(variance, dtype=np.float64)))
    a, b = law
    noise = rng.standard_normal((int(n), *clean.shape))
    base = np.sqrt(a * clean + b)
    medians = []
    for c in factors:
        frames = integer_roundtrip(clean + np.sqrt(c) * base * noise, **encoding)
        medians.append(float(np.mean(frames.astype(np.float64).var(axis=0).mean(axis=-1))))
    logs = np.log(np.maximum(medians, 1e-300))
    order = np.argsort(logs, kind="stable")
    c = float(np.exp(np.interp(np.log(max(target, 1e-300)), logs[order],
                               np.log(factors)[order])))
    return a * c, b * c
