"""The fields every registered statistic sees, in left-view coordinates (paper Sec. 2.2).

:class:`AlignedFields` holds :math:`\\sigma_L^2`, the warped :math:`\\hat\\sigma_{R\\to L}^2`
and the unaligned :math:`\\sigma_R^2`, plus named control fields computed on first use
(:func:`aligned_fields`): the seed-mean intensities, the null warps and the sensor baselines.
The same builder runs on the split halves and the seed subsets, so every statistic is
defined on them as on the full estimate.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .bootstrap import BootstrapSettings
from .warp import WarpPlan, warp_finite


class MissingField(KeyError):
    """A statistic asked for a field this run does not have (the reason says which)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else "missing field"


class AlignedFields:
    """:math:`\\sigma_L^2`, :math:`\\hat\\sigma_{R\\to L}^2`, :math:`\\sigma_R^2` and lazy
    control fields, all (H, W) float64 in left-view coordinates.

    Parameters
    ----------
    left : numpy.ndarray
        :math:`\\sigma_L^2` (Eq. 1).
    warped : numpy.ndarray
        :math:`\\hat\\sigma_{R\\to L}^2` (Eq. 2); 0 outside the warp's valid set.
    right : numpy.ndarray
        :math:`\\sigma_R^2` at the same pixel positions, unaligned; NaN where a render was
        non-finite.
    extra : dict, optional
        Name to an array or to a zero-argument function computing it (called once). Read
        with ``fields["name"]``; a missing name raises :class:`MissingField`.
    missing : dict, optional
        Name to the reason a field is absent (e.g. no seed mean in the variance store).
    """

    def __init__(self, left, warped, right, *, extra: dict | None = None, missing=None):
        self.left = left
        self.warped = warped
        self.right = right
        self._extra = dict(extra or {})
        self._missing = dict(missing or {})
        self._cache: dict[str, Any] = {}

    def __getitem__(self, name: str):
        if name in self._cache:
            return self._cache[name]
        if name not in self._extra:
            raise MissingField(self._missing.get(name, f"no {name} field in this run"))
        value = self._extra[name]
        value = value() if callable(value) else value
        self._cache[name] = value
        return value

    def __contains__(self, name: str) -> bool:
        return name in self._extra


@dataclass(frozen=True)
class AnalysisSettings:
    """``analysis`` and ``controls`` settings of the correlation rows."""

    min_pixels: int = 30
    bootstrap: BootstrapSettings = field(default_factory=BootstrapSettings)
    trim_fraction: float = 0.001
    firefly_factor: float = 100.0
    null_shift: float = 8.0


def channel_mean(mean) -> np.ndarray:
    """The RGB mean :math:`\\mu = \\frac13\\sum_c \\bar I_c` of a seed mean (H, W, C)."""
    return np.asarray(mean, dtype=np.float64).mean(axis=-1)


def aligned_fields(
    left,
    right,
    warped,
    *,
    ground_truth_left=None,
    sign: int = 1,
    settings: AnalysisSettings | None = None,
    intensity: tuple | None = None,
    sensor: dict[str, Callable] | None = None,
    colour: tuple | None = None,
    quantisation: tuple | None = None,
) -> AlignedFields:
    """Build :class:`AlignedFields` with the control fields this run can compute.

    Parameters
    ----------
    left, right, warped : numpy.ndarray, shape (H, W)
        :math:`\\sigma_L^2`, :math:`\\sigma_R^2` (NaN where not finite) and
        :math:`\\hat\\sigma_{R\\to L}^2`.
    ground_truth_left : mapping, optional
        ``disparity`` and ``valid`` of the left view; needed by the null warps.
    sign : int
        The ground truth's ``disparity_sign``.
    settings : AnalysisSettings, optional
    intensity : tuple of numpy.ndarray (mu_left, mu_warped), optional
        :func:`channel_mean` of the left seed mean and the warped right one
        (:func:`warped_intensity`).
    sensor : dict, optional
        ``sensor_left``, ``sensor_warped``, ``sensor_sim_left``, ``sensor_sim_warped``: arrays
        or functions computing them (:mod:`stereovar.controls.sensor`).
    colour : tuple of numpy.ndarray (mean_left, mean_warped), optional
        The left seed mean and the right one warped into the left view, per channel
        (H, W, C) (:func:`warped_colour`): the intensity control's chromaticity
        (:func:`control_covariates`).
    quantisation : tuple of numpy.ndarray (q_left, q_warped), optional
        The variance the frames' integer encoding implies at each view's seed mean, the
        right view's warped into the left (:func:`seed_mean_controls`); None for float
        frames.
    """
    from ..controls.null_warps import flipped_warp, shifted_warp

    settings = settings or AnalysisSettings()
    extra: dict[str, Any] = {}
    missing = {}
    if ground_truth_left is not None:
        d = np.asarray(ground_truth_left["disparity"])
        valid = np.asarray(ground_truth_left["valid"])
        clean_right = np.where(np.isfinite(right), right, np.nan)
        extra["null_shift"] = lambda: shifted_warp(
            clean_right, d, settings.null_shift, sign=sign, valid=valid
        )
        extra["null_flip"] = lambda: flipped_warp(clean_right, d, sign=sign, valid=valid)
    else:
        for name in ("null_shift", "null_flip"):
            missing[name] = "no ground truth given for the null warps"
    if intensity is not None:
        from ..controls.intensity import relative_variance

        extra["mean_left"], extra["mean_warped"] = intensity
        extra["relative_left"] = lambda: relative_variance(left, intensity[0])
        extra["relative_warped"] = lambda: relative_variance(warped, intensity[1])
    else:
        for name in ("mean_left", "mean_warped", "relative_left", "relative_warped"):
            missing[name] = "the variance store has no seed mean"
    d_left = None if ground_truth_left is None else ground_truth_left["disparity"]
    extra["control_covariates"] = lambda: control_covariates(
        np.shape(left), colour=colour, quantisation=quantisation, disparity=d_left, sign=sign
    )
    for name in ("sensor_left", "sensor_warped", "sensor_sim_left", "sensor_sim_warped"):
        missing[name] = (
            "fewer than 2 seeds to simulate sensor frames"
            if sensor
            else "the variance store has no seed mean for the sensor model"
        )
    extra.update(sensor or {})
    return AlignedFields(left, warped, right, extra=extra, missing=missing)


def chromaticity(mean) -> tuple[np.ndarray, np.ndarray] | None:
    """:math:`(\\mu_R/\\bar\\mu, \\mu_B/\\bar\\mu)` of a seed mean (H, W, C), 1 where
    :math:`\\bar\\mu \\le 0`; None for fewer than 3 channels."""
    mean = np.asarray(mean, dtype=np.float64)
    if mean.ndim != 3 or mean.shape[-1] < 3:
        return None
    mu = mean[..., :3].mean(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = tuple(np.where(mu > 0, mean[..., c] / mu, 1.0) for c in (0, 2))
    return ratios[0], ratios[1]


COVARIATES_PER_VIEW = 5
"""Fields per view of :func:`control_covariates`: two of chromaticity, the quantisation
variance, :math:`x` and :math:`y`."""


def control_covariates(shape, *, colour=None, quantisation=None, disparity=None,
                       sign: int = 1) -> tuple:
    """What the intensity control reads beside :math:`\\ln\\bar\\mu`
    (:func:`stereovar.controls.covariates.fit_control`), as (H, W) fields in left-view
    coordinates: each view's chromaticity (:func:`chromaticity`, when ``colour`` is given),
    the variance its integer encoding implies (``quantisation``, when the frames were
    stored as integers) and each pixel's position on its own sensor,

    .. math:: (x_L, y), \\qquad (x_R, y) = (x_L + s\\,d_L,\\ y)

    (Eq. 2's relation, paper Sec. 2.2; :math:`x_R = x_L` without a disparity).

    Returns
    -------
    tuple of numpy.ndarray
        :data:`COVARIATES_PER_VIEW` fields of the left view, then the right view's in the
        same order: the two chromaticity coordinates (1 without colour), the quantisation
        variance (0 for float frames), :math:`x` and :math:`y`. A constant term has
        nothing to fit and the control drops it.
    """
    h, w = (int(s) for s in shape[:2])
    y, x = np.indices((h, w), dtype=np.float64)
    x_right = x if disparity is None else x + sign * np.nan_to_num(
        np.asarray(disparity, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    ones, zeros = np.ones((h, w)), np.zeros((h, w))
    ratios = [(ones, ones), (ones, ones)]
    if colour is not None:
        found = [chromaticity(mean) for mean in colour]
        if all(r is not None for r in found):
            ratios = found
    q = quantisation if quantisation is not None else (zeros, zeros)
    return (*ratios[0], q[0], x, y, *ratios[1], q[1], x_right, y)


def warped_colour(mean_right, ground_truth_left, *, sign: int, plan=None) -> np.ndarray:
    """The right view's seed mean warped into the left view channel by channel (Eq. 2);
    NaN outside the warp's valid set."""
    plan = plan or WarpPlan(
        np.asarray(ground_truth_left["disparity"]),
        sign=sign,
        valid=np.asarray(ground_truth_left["valid"]),
    )
    mean_right = np.asarray(mean_right, dtype=np.float64)
    return np.stack(
        [np.where(plan.omega, plan.apply(mean_right[..., c]), np.nan)
         for c in range(mean_right.shape[-1])], axis=-1)


def seed_mean_controls(mean_left, mean_right, ground_truth_left, *, sign: int, plan=None,
                       encoding=None):
    """The intensity control's inputs from the two seed means: ``intensity``
    (:math:`\\mu_L`, :math:`\\hat\\mu_{R\\to L}`, the RGB means), ``colour`` (the left
    seed mean and the right one warped, per channel) and, for frames stored as integers
    (``encoding``: ``bits``, ``transfer``, ``scale``), ``quantisation``: the variance the
    encoding implies at each view's own seed mean
    (:func:`stereovar.controls.quantisation.quantisation_variance`), the right view's warped
    as its variance is. The keyword arguments of :func:`aligned_fields`."""
    from ..controls.quantisation import quantisation_variance

    plan = plan or WarpPlan(
        np.asarray(ground_truth_left["disparity"]),
        sign=sign,
        valid=np.asarray(ground_truth_left["valid"]),
    )
    colour = warped_colour(mean_right, ground_truth_left, sign=sign, plan=plan)
    out = {
        "intensity": (channel_mean(mean_left), colour.mean(axis=-1)),
        "colour": (np.asarray(mean_left, dtype=np.float64), colour),
    }
    q_left = quantisation_variance(mean_left, encoding)
    if q_left is not None:
        q_right = quantisation_variance(mean_right, encoding)
        out["quantisation"] = (q_left, np.where(plan.omega, plan.apply(q_right), 0.0))
    return out


def warped_intensity(mean_right, ground_truth_left, *, sign: int, plan=None) -> np.ndarray:
    """The right view's RGB-mean seed mean warped into the left view (Eq. 2); NaN outside
    the warp's valid set. ``plan``: the scene's :class:`~stereovar.statistics.warp.WarpPlan`
    when already built."""
    plan = plan or WarpPlan(
        np.asarray(ground_truth_left["disparity"]),
        sign=sign,
        valid=np.asarray(ground_truth_left["valid"]),
    )
    return np.where(plan.omega, plan.apply(channel_mean(mean_right)), np.nan)


def warp_field(right, ground_truth_left, *, sign: int, plan=None) -> np.ndarray:
    """Any right-view (H, W) field warped into the left view (Eq. 2), NaN outside the valid
    set and where a non-finite right pixel has non-zero weight. ``plan``: the scene's
    :class:`~stereovar.statistics.warp.WarpPlan` when already built."""
    warped, omega, clean = warp_finite(
        right,
        np.asarray(ground_truth_left["disparity"]),
        sign=sign,
        valid=np.asarray(ground_truth_left["valid"]),
        plan=plan,
    )
    return np.where(omega & clean, warped, np.nan)
