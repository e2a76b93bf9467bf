"""The renders' camera law and the planted strength they show beyond it: the first step of
one scene's calibration (:mod:`stereovar.calibration`).

Every design is drawn at a camera law :math:`a\\mu + b` fitted to the renders' own Eq. 1
field, around the scene's clean images (:func:`scene_law`). The renders' strength
(:func:`render_strength`) is the spread of :math:`\\ln\\sigma_L^2` that neither intensity
nor the estimation noise of a ``camera`` null at the same :math:`N` explains
(:func:`camera_residual_variance`); the planted designs are multiples of it.
"""

from __future__ import annotations

import numpy as np

from ..seeding import derive_seed
from .pipelines import dequantised_mean, encoded_clean, encoded_frames
from .scene_frames import SceneFrames
from .synthesis import camera_law, draw_frames, variance_fields


def scene_law(scene: SceneFrames, seed: int = 0) -> tuple[tuple[float, float], dict]:
    """The camera law every design is drawn at and the clean images it is drawn around.

    The law is fitted to the left view's Eq. 1 field over its valid pixels
    (:func:`~stereovar.calibration.synthesis.camera_law`), the clean images are the seed
    means. Renders stored as integers (``scene.encoding``) give the law before the encoding
    instead (:func:`~stereovar.calibration.pipelines.encoded_clean`, drawn with its own
    seed) and the clean images behind their seed means
    (:func:`~stereovar.calibration.pipelines.dequantised_mean`).

    Returns
    -------
    law : (a, b)
    clean : dict
        View to the clean image (H, W, C).
    """
    mu = np.asarray(scene.mean["left"], dtype=np.float64).mean(axis=-1)
    gt_valid = np.asarray(scene.ground_truth["left"]["valid"], dtype=bool)
    law = camera_law(scene.variance["left"], mu, gt_valid)
    clean = scene.mean
    if scene.encoding:  # the law before the encoding, around the clean image behind it
        law, _ = encoded_clean(
            scene.mean["left"], scene.variance["left"], law, scene.n_seeds,
            np.random.default_rng(derive_seed("calibration-law", seed, scene.label)),
            scene.encoding)
        clean = {v: dequantised_mean(m, law, scene.encoding, scene.n_seeds)
                 for v, m in scene.mean.items()}
    return law, clean


def camera_residual_variance(scene: SceneFrames, law, rng: np.random.Generator) -> float:
    """The estimation noise of :math:`\\ln\\sigma_L^2` at the scene's :math:`N`: the
    variance of the intensity control's residual on ``camera`` null frames (the
    :math:`\\operatorname{Var}(e_L^0)` of :func:`render_strength`), drawn with ``rng``."""
    from ..estimators.seeds import variance_field

    v = variance_fields(
        "camera", 0.0, mean=scene.mean, law=law, render_variance=scene.variance, rng=rng
    )
    _, null_field = variance_field(encoded_frames(
        draw_frames(scene.mean["left"], v["left"], scene.n_seeds, rng,
                    channel_correlation=scene.channel_correlation), scene.encoding))
    return _residual_variance(null_field, scene.mean["left"], scene)


def render_strength(scene: SceneFrames, settings, camera_rows_residual_var: float) -> float:
    """The planted strength the renders show: the standard deviation of the part of
    :math:`\\ln\\sigma_L^2` that intensity does not explain, beyond estimation noise.

    .. math::

        \\hat s = \\sqrt{\\max\\bigl(\\operatorname{Var}(e_L) - \\operatorname{Var}(e_L^{0}),
            0\\bigr)}

    with :math:`e_L` the intensity control's residual of the renders' left field over the
    valid pixels (:func:`stereovar.controls.intensity.intensity_residuals`) and
    :math:`e_L^0` the same residual on the ``camera`` null (estimation noise alone, same
    :math:`N`).
    """
    residual_var = _residual_variance(scene.variance["left"], scene.mean["left"], scene)
    return float(np.sqrt(max(residual_var - camera_rows_residual_var, 0.0)))


def _residual_variance(variance, mean, scene: SceneFrames) -> float:
    from ..controls.intensity import intensity_residuals
    from ..statistics.robust import log_floor

    gt = scene.ground_truth["left"]
    ok = np.asarray(gt["valid"], dtype=bool) & np.isfinite(variance)
    mu = np.asarray(mean, dtype=np.float64).mean(axis=-1)
    ok &= np.isfinite(mu)
    lv, _ = log_floor(np.asarray(variance, dtype=np.float64)[ok])
    lm, _ = log_floor(mu[ok])
    e = intensity_residuals(lv, lm)
    return float(np.nanvar(e))
