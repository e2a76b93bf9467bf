"""The quantisation term of the intensity control: the variance an integer encoding implies.

Frames stored as integers (8-bit PNG through the sRGB curve, as Kubric and BlenderProc ship)
hold only code values. Where the noise is below about one code (a denoised render), a pixel's
:math:`N` frames take one or two neighbouring codes, and its Eq. 1 variance is then fixed by
its seed mean: with codes decoding to :math:`D_k < D_{k+1}` and a share :math:`p` of the
frames at the upper one, the mean is :math:`\\bar I = D_k + p\\,(D_{k+1} - D_k)` and

.. math::

    \\sigma^2 = \\frac{N}{N - 1}\\, p\\,(1 - p)\\,(D_{k+1} - D_k)^2 .

That sawtooth in the seed mean is the same in both views wherever they see the same clean
value (an integer disparity, a flat surface), so it correlates across views with no Monte
Carlo cue at all. :func:`quantisation_variance` computes it from the seed mean and the
encoding, and the control (:func:`stereovar.controls.covariates.fit_control`) removes it as
it removes intensity, colour and position. Where it explains the whole field, the intensity
control is undefined: the variance is a function of the seed mean, with nothing left for a
Monte Carlo cue to show in.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

CODE_TOLERANCE = 1e-4
"""A seed mean within this share of a step of a code is on it: the frames decode to float32,
whose rounding (about :math:`6\\cdot 10^{-8}` of the value, a few :math:`10^{-6}` of an 8-bit
step) would otherwise give a pixel whose frames all agree a tiny, spurious variance. A
share of frames at the upper code is a multiple of :math:`1/N`, far above it."""


@lru_cache(maxsize=8)
def code_values(bits: int, transfer: str = "srgb", scale: float = 1.0) -> np.ndarray:
    """The linear value every code of the encoding decodes to, as the import decodes it
    (:func:`stereovar.io.images.read_image`): :math:`D_k = s\\,T^{-1}(k / (2^B - 1))`,
    rounded to float32 as the frames are.

    Examples
    --------
    >>> code_values(8, "linear")[[0, 1, 255]].round(6).tolist()
    [0.0, 0.003922, 1.0]
    """
    from ..io.transfer import srgb_to_linear

    full = 2 ** int(bits) - 1
    v = np.arange(full + 1, dtype=np.float64) / full
    values = srgb_to_linear(v) if transfer == "srgb" else v
    # as the import stores them: float32, whose rounding at 16 bits is a tenth of a step
    out = (np.asarray(values, dtype=np.float64) * float(scale)).astype(np.float32)
    out = out.astype(np.float64)
    out.setflags(write=False)
    return out


def quantisation_variance(mean, encoding: dict | None) -> np.ndarray | None:
    """The Eq. 1 variance an integer encoding implies at each pixel's seed mean, averaged
    over channels as Eq. 1 is (the module's equation without :math:`N/(N-1)`).

    .. math::

        q = \\frac1C \\sum_c p_c (1 - p_c)\\,(D_{k_c + 1} - D_{k_c})^2, \\qquad
        p_c = \\frac{\\bar I_c - D_{k_c}}{D_{k_c + 1} - D_{k_c}}

    with :math:`k_c` the code just below the channel's mean. 0 at a mean on a code (every
    frame the same) and at or beyond the ends of the range.

    Parameters
    ----------
    mean : array_like (H, W, C) or (H, W)
        The seed mean, linear, as imported.
    encoding : dict or None
        ``bits``, ``transfer`` and ``scale`` of the stored frames
        (:func:`stereovar.jobs.calibration.stored_encoding`); None for float frames.

    Returns
    -------
    numpy.ndarray (H, W) or None
        None without an encoding.

    Examples
    --------
    Four frames of a linear 8-bit channel, two at code 10 and two at 11: the mean sits
    halfway, and Eq. 1's variance is :math:`\\frac43 \\cdot \\frac14` of a code squared.

    >>> frames = np.array([10, 10, 11, 11]) / 255.0
    >>> q = quantisation_variance(frames.mean().reshape(1, 1), {"bits": 8,
    ...                           "transfer": "linear", "scale": 1.0})
    >>> bool(np.isclose(4 / 3 * q[0, 0], frames.var(ddof=1)))
    True
    """
    if not encoding:
        return None
    table = code_values(int(encoding["bits"]), str(encoding.get("transfer", "srgb")),
                        float(encoding.get("scale", 1.0)))
    m = np.asarray(mean, dtype=np.float64)
    if m.ndim == 2:
        m = m[..., None]
    k = np.clip(np.searchsorted(table, m, side="right") - 1, 0, table.size - 2)
    low, step = table[k], table[k + 1] - table[k]
    with np.errstate(invalid="ignore", divide="ignore"):
        p = np.clip((m - low) / step, 0.0, 1.0)
    # a mean on a code, read back through float32, lands up to a few 1e-6 of a step off it
    p = np.where((p < CODE_TOLERANCE) | (p > 1.0 - CODE_TOLERANCE), 0.0, p)
    q = np.where(np.isfinite(p), p * (1.0 - p) * step * step, 0.0)
    return q.mean(axis=-1)


FIXED_SHARE = 0.9
"""The share of pixels whose Eq. 1 variance equals the variance their seed mean implies
(:func:`fixed_share`) at or above which the intensity-controlled statistic is undefined.

There the frames' variance is the encoding's, fixed by the mean, at nearly every pixel: what
is left after the control is the few pixels whose frames span three codes, and they fall
where both views see the same clean value. On 8-bit sRGB at an integer disparity, at 0.2 DN
of noise (99% of the pixels fixed) the data read 0.06 and their encoded null 0.01; at 0.3 DN
(76% fixed) 0.009-0.013 against 0.001-0.007, at 0.4 DN (36%) about 0 for both."""


def fixed_share(variance, quantisation) -> float:
    """The share of pixels whose Eq. 1 variance equals, to 0.1%, the variance the encoding
    implies at their seed mean (:func:`quantisation_variance`): those whose frames all fall
    on one code or two neighbouring ones. NaN without finite pairs.

    Examples
    --------
    >>> fixed_share(np.array([0.0, 1e-4, 3e-4]), np.array([0.0, 1e-4, 1e-4]))
    0.6666666666666666
    """
    v = np.asarray(variance, dtype=np.float64)
    q = np.asarray(quantisation, dtype=np.float64)
    ok = np.isfinite(v) & np.isfinite(q)
    if not ok.any():
        return float("nan")
    return float(np.mean(np.isclose(v[ok], q[ok], rtol=1e-3, atol=0.0)))
