"""The probe's positive control: renders with a planted cross-view variance cue.

The matcher is trained and tested on frames drawn the way the calibration draws its planted
design (:mod:`stereovar.calibration.synthesis`, ``DESIGN.md``, Calibration): around each
view's seed mean :math:`\\bar I_V`, with per-pixel variance

.. math::

    v_V = (a\\mu_V + b)\\, e^{s z_V - s^2/2}, \\qquad
    z_R(x, y) = z_L\\bigl(x - s_d\\, d_R(x, y),\\, y\\bigr),

the camera law :math:`a\\mu + b` fitted to the renders times a smooth unit-variance pattern
:math:`z` of the left view carried into the right view by the right view's ground-truth
disparity (:math:`s_d` the ``disparity_sign``). The strength :math:`s` is the standard
deviation of the planted :math:`\\ln v`; the renders' own strength, measured as the
calibration measures it (:func:`renders_strength`), sets the scale of the probe's planted
series. At :math:`s = 0` the frames are the camera null: noise of the renders' level with no
cue.
"""

from __future__ import annotations

import numpy as np

from ..calibration.law import camera_residual_variance, render_strength
from ..calibration.scene_frames import SceneFrames
from ..calibration.synthesis import camera_law, draw_frames, planted_pattern, variance_fields

__all__ = ["planted_views", "renders_law", "renders_strength"]


def planted_views(
    mean_left,
    mean_right,
    truth_left,
    truth_right,
    *,
    sign: int,
    law,
    strength: float,
    n: int,
    rng: np.random.Generator,
    channel_correlation: float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """:math:`N` frames per view with a planted cue of strength :math:`s`, the channels of a
    pixel correlated as ``channel_correlation`` (the renders', a path tracer's near 1;
    :func:`stereovar.calibration.synthesis.draw_frames`).

    .. math::

        I_V^{(n)} = \\bar I_V + \\sqrt{v_V}\\,\\varepsilon_V^{(n)}, \\qquad
        v_V = (a\\max(\\bar I_V, 0) + b)\\, e^{s z_V - s^2/2}

    per channel, :math:`\\varepsilon` standard normal per pixel, channel, frame and view, and
    :math:`(z_L, z_R)` from :func:`stereovar.calibration.synthesis.planted_pattern` with the
    right view's disparity and validity (an independent pattern where the right pixel is
    occluded or sees outside the left image).

    Parameters
    ----------
    mean_left, mean_right : array_like, shape (H, W, 3)
        Each view's clean image :math:`\\bar I_V`, linear.
    truth_left, truth_right : dict
        Each view's ground truth, ``{"disparity", "valid"}`` (H, W); the right view's carries
        the pattern.
    sign : {1, -1}, keyword-only
        ``disparity_sign``: the right pixel of left pixel :math:`x` is at :math:`x + s_d d`.
    law : (float, float), keyword-only
        :math:`(a, b)` (:func:`renders_law`).
    strength : float, keyword-only
        :math:`s`, the standard deviation of the planted :math:`\\ln v`.
    n : int, keyword-only
        :math:`N`.
    rng : numpy.random.Generator, keyword-only
    channel_correlation : float, keyword-only
        :math:`\\rho \\in [0, 1]` between the channels of a pixel.

    Returns
    -------
    left, right : numpy.ndarray, float32, shape (N, H, W, 3)
    """
    sign = int(sign)
    if sign not in (1, -1):
        raise ValueError(f"sign must be 1 or -1, got {sign}")
    if float(strength) < 0:
        raise ValueError(f"the planted strength must be at least 0, got {strength}")
    mean = {
        "left": np.asarray(mean_left, dtype=np.float64),
        "right": np.asarray(mean_right, dtype=np.float64),
    }
    shape = mean["left"].shape[:2]
    for view, truth in (("left", truth_left), ("right", truth_right)):
        if np.shape(truth["disparity"]) != shape or mean[view].shape[:2] != shape:
            raise ValueError(f"the {view} view's mean and ground truth differ in shape")
    pattern = planted_pattern(
        truth_right["disparity"], truth_right["valid"], sign=sign, rng=rng
    )
    v = variance_fields(
        "planted", float(strength), mean=mean, law=law, render_variance={}, pattern=pattern,
        rng=rng,
    )
    return tuple(
        draw_frames(mean[view], v[view], int(n), rng, channel_correlation=channel_correlation)
        for view in ("left", "right")
    )


def _scene(renders_left, truth_left) -> SceneFrames:
    """The calibration's view of one scene's left renders (its Eq. 1 field by seeds)."""
    from ..estimators.seeds import variance_field

    stack = np.asarray(renders_left, dtype=np.float64)
    if stack.ndim != 4 or stack.shape[0] < 2:
        raise ValueError(f"renders must have shape (N >= 2, H, W, C), got {stack.shape}")
    mean, variance = variance_field(stack)
    return SceneFrames(
        mean={"left": mean},
        variance={"left": variance},
        ground_truth={"left": truth_left},
        glass=np.zeros(variance.shape, dtype=bool),
        sign=1,
        n_seeds=stack.shape[0],
        label="probe",
    )


def renders_law(renders_left, truth_left) -> tuple[float, float]:
    """The camera law :math:`(a, b)` of the left renders: their Eq. 1 variance against the
    seed mean's grey over the valid pixels, fitted as the calibration fits it
    (:func:`stereovar.calibration.synthesis.camera_law`).

    Parameters
    ----------
    renders_left : array_like, shape (N, H, W, 3)
    truth_left : dict
        ``{"disparity", "valid"}`` (H, W).
    """
    scene = _scene(renders_left, truth_left)
    mu = scene.mean["left"].mean(axis=-1)
    return camera_law(scene.variance["left"], mu, np.asarray(truth_left["valid"], dtype=bool))


def renders_strength(renders_left, truth_left, *, rng: np.random.Generator, law=None) -> float:
    """The planted strength the renders show, as the calibration measures it.

    .. math::

        \\hat s = \\sqrt{\\max\\bigl(\\operatorname{Var}(e_L) - \\operatorname{Var}(e_L^{0}),
            0\\bigr)}

    with :math:`e_L` the intensity control's residual of the renders' :math:`\\ln\\sigma_L^2`
    over the valid pixels and :math:`e_L^0` the same on camera-null frames of the same
    :math:`N` (:func:`stereovar.calibration.replicates.render_strength` and
    :func:`stereovar.calibration.replicates.camera_residual_variance`).

    Parameters
    ----------
    renders_left : array_like, shape (N, H, W, 3)
        The left view's renders, seed index first.
    truth_left : dict
        ``{"disparity", "valid"}`` (H, W).
    rng : numpy.random.Generator, keyword-only
        Draws the camera-null frames.
    law : (float, float), keyword-only, optional
        The camera law; default :func:`renders_law`.

    Returns
    -------
    float
    """
    scene = _scene(renders_left, truth_left)
    if law is None:
        mu = scene.mean["left"].mean(axis=-1)
        law = camera_law(scene.variance["left"], mu, np.asarray(truth_left["valid"], bool))
    noise_var = camera_residual_variance(scene, law, rng)
    return render_strength(scene, None, noise_var)
