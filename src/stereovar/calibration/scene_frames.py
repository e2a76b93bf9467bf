"""What the calibration takes from one scene of the run: its seed means, the renders' Eq. 1
field, its ground truth and :math:`N` (:class:`SceneFrames`), read by every step after it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SceneFrames:
    """What the calibration takes from one scene of the run.

    Attributes
    ----------
    mean : dict
        View to the seed mean :math:`\\bar I_V` (H, W, C).
    variance : dict
        View to the renders' Eq. 1 field :math:`\\sigma_V^2` (H, W).
    ground_truth : dict
        View to ``{"disparity", "valid"}`` (H, W).
    glass : numpy.ndarray of bool (H, W)
        The left view's glass mask.
    sign : int
        ``disparity_sign``.
    n_seeds : int
        :math:`N`, the frames per view of every replicate.
    label : str
        The scene and SPP (seeds the draws).
    aux : dict, optional
        View to ``{"albedo", "normal"}`` for the denoiser, as the run gives it.
    encoding : dict, optional
        How the frames were stored when they were integers (an audit's PNG or HDF5 renders):
        ``bits``, ``transfer`` and ``scale``
        (:func:`~stereovar.calibration.pipelines.integer_roundtrip`); every synthetic frame
        then passes through the same encoding, at the camera law it had before it
        (:func:`~stereovar.calibration.pipelines.encoded_law`).
    channel_correlation : float, optional
        The renders' noise correlation between the channels of a pixel
        (:func:`~stereovar.calibration.synthesis.channel_correlation`; a path tracer's is near
        0.9): the synthetic frames' channels share their noise as much, so that Eq. 1's
        estimation noise, and with it the renders' strength, is the renders'.
    window, max_disparity : int, optional
        The variance-matching cost's patch side and largest disparity, as the intervention
        scans the renders (``intervention.window``; ``max_disparity`` None: the largest
        ground truth plus ``intervention.disparity_margin``).
    sensor : stereovar.controls.sensor.SensorModel, optional
        The run's camera (``controls.sensor``), for the ``sensor_sim`` baseline.
    """

    mean: dict
    variance: dict
    ground_truth: dict
    glass: np.ndarray
    sign: int
    n_seeds: int
    label: str
    aux: dict | None = None
    encoding: dict | None = None
    channel_correlation: float = 0.0
    window: int = 5
    max_disparity: int | None = None
    sensor: object = None
