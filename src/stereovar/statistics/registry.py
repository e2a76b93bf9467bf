"""The statistics registry: every per-region statistic and control of the aligned fields.

A statistic is a pair of fields in left-view coordinates and an optional transform of their
values over a region; its number is Pearson's :math:`\\rho` of the transformed values. So
every statistic gets the same machinery (:func:`evaluate`): the Fisher-z interval (assuming
independent pixels), the spatial block bootstrap interval
(:mod:`stereovar.statistics.bootstrap`), the share of the covariance in the top 0.1% of
products, the firefly count and, where the fields are Eq. 1 estimates, the split-half
reliability and the attenuation-corrected :math:`\\rho`
(:mod:`stereovar.statistics.reliability`). The correlation rows
(``results/.../correlation/{scene}/spp{spp}.csv``), Table 1 and the figures iterate over
:data:`METHODS`, so a new statistic is one pair function plus one :func:`register_method`
call; its name becomes the rows' ``method`` value.

Registered here (paper Sec. 2.3, 3.2, and the controls of :mod:`stereovar.controls`):

``warp``
    Eq. 3: Pearson of :math:`\\sigma_L^2` and the warped :math:`\\hat\\sigma_{R\\to L}^2`.
    The primary statistic (:data:`PRIMARY_METHOD`).
``spearman``, ``log``, ``trimmed``
    Robust versions: Spearman's rank correlation; Pearson of :math:`\\ln\\sigma^2`; Pearson
    after dropping the top ``analysis.trim_fraction`` of each field.
``no_warp``
    The same pixels without the alignment (Table 1's ``mean_rho_no_warp``).
``null_shift``, ``null_flip``
    Wrong alignments: the disparity plus ``controls.null_shift`` pixels; the right field
    flipped upside down.
``partial``, ``relative``
    The intensity control: residuals of :math:`\\ln\\sigma^2` given :math:`\\ln\\mu`;
    :math:`\\sigma^2/\\mu^2`.
``sensor``, ``sensor_sim``
    A Poisson-Gaussian camera on the seed mean: its analytic variance field, and Eq. 1
    over :math:`N` simulated frames per view.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..registry import Registry
from .bootstrap import (
    FEWER_THAN_2_TILES,
    bootstrap_replicates,
    draw_counts,
    percentile_interval,
    tile_sums,
)
from .correlation import CONSTANT, fisher_interval, undefined_result
from .fields import AlignedFields, AnalysisSettings, MissingField
from .robust import firefly_count, log_floor, ranks, top_share, trim_mask

__all__ = ["AlignedFields", "METHODS", "Method", "PRIMARY_METHOD", "register_method"]


@dataclass(frozen=True)
class Method:
    """A registered statistic.

    Attributes
    ----------
    pair : callable
        ``pair(fields) -> (a, b, *covariates)``: (H, W) arrays in left-view coordinates.
    description : str
    transform : callable or None
        ``transform(values, settings) -> (a, b)`` or ``(a, b, keep)`` on the region's
        finite values (a tuple of 1-D arrays in the order ``pair`` returns them); ``keep``
        (bool) drops pairs. None: Pearson of ``a`` and ``b`` as they are.
    estimator_noise : bool
        Report split-half reliability and the attenuation-corrected rho (False for the sensor
        baselines, whose fields are not Eq. 1 of the renders, and for the null warps, whose
        level is the point).
    curve : bool
        Report this statistic at :math:`N' < N` seeds too.
    """

    pair: Callable[..., tuple]
    description: str
    transform: Callable | None = None
    estimator_noise: bool = True
    curve: bool = False


METHODS = Registry("statistic")
"""Name to :class:`Method`, in the order rows and table columns appear."""

PRIMARY_METHOD = "warp"
"""The statistic Table 1's ``mean_rho`` and Table 2's ``rho_{region}`` report."""


def register_method(
    name: str,
    description: str,
    *,
    transform: Callable | None = None,
    estimator_noise: bool = True,
    curve: bool = False,
    replace: bool = False,
):
    """Decorator registering ``pair(fields) -> (a, b, ...)`` as statistic ``name``."""

    def decorator(pair):
        METHODS.register(
            name,
            Method(pair, description, transform, estimator_noise, curve),
            replace=replace,
        )
        return pair

    return decorator


def secondary_methods() -> tuple[str, ...]:
    """Every registered statistic but :data:`PRIMARY_METHOD`."""
    return tuple(m for m in METHODS.names() if m != PRIMARY_METHOD)


# ---------------------------------------------------------------- evaluation


def region_values(arrays, transform, mask, settings: AnalysisSettings):
    """The transformed pairs of one region and the pixels they come from.

    Parameters
    ----------
    arrays : sequence of array_like (H, W)
        A method's ``pair`` output.
    transform : callable or None
        The method's transform.
    mask : array_like of bool (H, W)
    settings : AnalysisSettings

    Returns
    -------
    a, b : numpy.ndarray (n,)
        Transformed values (finite).
    index : numpy.ndarray of int (n,)
        Flat pixel index of each pair.
    raw : tuple of numpy.ndarray
        ``a`` and ``b`` before the transform, at the same pixels.
    n_nonfinite : int
        Pixels of ``mask`` dropped because a field (or its transform) was not finite.
    """
    arrays = [np.asarray(f, dtype=np.float64) for f in arrays]
    mask = np.asarray(mask, dtype=bool)
    index = np.flatnonzero(mask)
    values = [f.ravel()[index] for f in arrays]
    ok = np.logical_and.reduce([np.isfinite(v) for v in values])
    n_nonfinite = int(ok.size - ok.sum())
    values = [v[ok] for v in values]
    index = index[ok]
    raw = (values[0], values[1])
    if transform is not None and values[0].size:
        out = transform(tuple(values), settings)
        a, b = out[0], out[1]
        keep = np.isfinite(a) & np.isfinite(b)
        if len(out) > 2:
            keep &= out[2]
        n_nonfinite += int((~(np.isfinite(a) & np.isfinite(b))).sum())
        a, b, index = a[keep], b[keep], index[keep]
        raw = (raw[0][keep], raw[1][keep])
    else:
        a, b = values[0], values[1]
    return a, b, index, raw, n_nonfinite


def pearson_point(a, b) -> float:
    """Pearson's :math:`\\rho` of two value arrays (NaN when either is constant)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.size < 2:
        return float("nan")
    da, db = a - a.mean(), b - b.mean()
    sa, sb = np.abs(da).max(), np.abs(db).max()
    if not (sa > 0 and sb > 0):
        return float("nan")
    da, db = da / sa, db / sb
    # einsum, not BLAS: a threaded BLAS dot stalls when parallel jobs share the cores
    sab, saa, sbb = (np.einsum("i,i->", x, y) for x, y in ((da, db), (da, da), (db, db)))
    return float(np.clip(sab / np.sqrt(saa * sbb), -1.0, 1.0))


class BootstrapDraws:
    """Replicate draw counts shared by every statistic of one region with the same tiles,
    so their bootstrap intervals come from the same resamples."""

    def __init__(self, settings, seed):
        self.settings = settings
        self.seed = seed
        self._cache: dict[int, np.ndarray] = {}

    def counts(self, n_tiles: int) -> np.ndarray:
        if n_tiles not in self._cache:
            self._cache[n_tiles] = draw_counts(n_tiles, self.settings.reps, self.seed)
        return self._cache[n_tiles]


def evaluate(
    method: Method,
    fields: AlignedFields,
    mask,
    *,
    settings: AnalysisSettings,
    labels=None,
    draws: BootstrapDraws | None = None,
) -> dict:
    """One statistic over one region: :math:`\\rho` with both intervals and the diagnostics.

    .. math::

        \\rho = \\mathrm{corr}\\bigl(T(a), T(b)\\bigr)\\big|_{\\Omega_r}

    with :math:`(a, b)` the method's fields and :math:`T` its transform, plus the Fisher-z
    interval (:func:`~stereovar.statistics.correlation.fisher_interval`), the spatial block
    bootstrap's percentile interval over the tiles of ``labels`` (ranks, logarithms and the
    trimming are computed once over the region and the replicates resample the transformed
    pairs tile by tile), :func:`~stereovar.statistics.robust.top_share` of the transformed
    values and :func:`~stereovar.statistics.robust.firefly_count` of the raw ones.

    Returns
    -------
    dict
        The :data:`~stereovar.statistics.correlation.RESULT_KEYS`.
    """
    try:
        a, b, index, raw, n_nonfinite = region_values(
            method.pair(fields), method.transform, mask, settings
        )
    except MissingField as missing:
        return undefined_result(0, 0, str(missing))
    n = int(a.size)
    if n < settings.min_pixels:
        return undefined_result(
            n, n_nonfinite, f"fewer than {settings.min_pixels} valid pixels (n={n})"
        )
    rho = pearson_point(a, b)
    if not np.isfinite(rho):
        return undefined_result(n, n_nonfinite, CONSTANT)
    result = {
        **undefined_result(n, n_nonfinite, ""),
        "rho": rho,
        **fisher_interval(rho, n),
        "mean_a": float(raw[0].mean()),
        "top_share": top_share(a, b),
        "n_fireflies": firefly_count(raw[0], raw[1], settings.firefly_factor),
    }
    if labels is not None and draws is not None:
        sums = tile_sums(a, b, np.asarray(labels).ravel()[index])
        result["n_tiles"] = int(sums.shape[0])
        if sums.shape[0] < 2:
            result["reason"] = FEWER_THAN_2_TILES
        else:
            reps = bootstrap_replicates(sums, draws.counts(sums.shape[0]))
            result["boot_low"], result["boot_high"] = percentile_interval(reps)
    return result


def point_estimate(method: Method, fields_a, fields_b, mask, settings, *, side: int) -> float:
    """:math:`\\rho` between one view's field in two estimates (e.g. the two split halves).

    ``side`` 0 compares the methods' ``a`` fields (left view), 1 the ``b`` fields (right
    view, warped); covariates are taken from the same view.
    """
    try:
        one = [np.asarray(f, dtype=np.float64) for f in method.pair(fields_a)]
        two = [np.asarray(f, dtype=np.float64) for f in method.pair(fields_b)]
    except MissingField:
        return float("nan")
    covariates = one[2:]
    if covariates:
        covariates = [covariates[side]] * 2
    a, b, _, _, _ = region_values(
        [one[side], two[side], *covariates], method.transform, mask, settings
    )
    if a.size < settings.min_pixels:
        return float("nan")
    return pearson_point(a, b)


# ---------------------------------------------------------------- transforms


def _ranked(values, settings):
    return ranks(values[0]), ranks(values[1])


def _logged(values, settings):
    return log_floor(values[0])[0], log_floor(values[1])[0]


def _trimmed(values, settings):
    return values[0], values[1], trim_mask(values[0], values[1], settings.trim_fraction)


def _partial(values, settings):
    from ..controls.intensity import partial_pair

    return partial_pair(*values)


# ---------------------------------------------------------------- the statistics


@register_method("warp", "Pearson of sigma_L^2 and the warped sigma_R^2 (Eq. 3)", curve=True)
def warped_pair(fields: AlignedFields):
    """Eq. 3: :math:`\\rho = \\mathrm{corr}(\\sigma_L^2, \\hat\\sigma_{R\\to L}^2)|_{\\Omega_r}`.

    .. math::

        \\rho = \\frac{\\sum_{i \\in \\Omega_r} (a_i - \\bar a)(b_i - \\bar b)}
            {\\sqrt{\\sum_i (a_i - \\bar a)^2 \\sum_i (b_i - \\bar b)^2}}, \\quad
        a = \\sigma_L^2,\\ b = \\hat\\sigma_{R\\to L}^2

    (paper Sec. 2.3).
    """
    return fields.left, fields.warped


@register_method(
    "spearman",
    "Spearman rank correlation of sigma_L^2 and the warped sigma_R^2",
    transform=_ranked,
)
def spearman_pair(fields: AlignedFields):
    """Spearman's :math:`\\rho_s`: Eq. 3 on mid-ranks over the region.

    .. math:: \\rho_s = \\mathrm{corr}\\bigl(R(\\sigma_L^2), R(\\hat\\sigma_{R\\to L}^2)\\bigr)
    """
    return fields.left, fields.warped


@register_method(
    "log",
    "Pearson of ln sigma^2 (floored at the smallest positive value)",
    transform=_logged,
    curve=True,
)
def log_pair(fields: AlignedFields):
    """Pearson of the logarithms (:func:`~stereovar.statistics.robust.log_floor`).

    .. math:: \\rho_{\\ln} = \\mathrm{corr}\\bigl(\\ln\\max(\\sigma_L^2, f_L),\\,
        \\ln\\max(\\hat\\sigma_{R\\to L}^2, f_R)\\bigr)
    """
    return fields.left, fields.warped


@register_method(
    "trimmed",
    "Pearson after dropping the top analysis.trim_fraction of each field",
    transform=_trimmed,
)
def trimmed_pair(fields: AlignedFields):
    """Eq. 3 without the top ``analysis.trim_fraction`` of each field
    (:func:`~stereovar.statistics.robust.trim_mask`)."""
    return fields.left, fields.warped


@register_method("no_warp", "Pearson of sigma_L^2 and the unaligned sigma_R^2 on the same pixels")
def unaligned_pair(fields: AlignedFields):
    """The no-warp baseline of paper Sec. 3.2: Eq. 3 without Eq. 2.

    .. math::

        \\rho_{\\text{no-warp}} = \\mathrm{corr}\\bigl(\\sigma_L^2(x, y),\\,
            \\sigma_R^2(x, y)\\bigr)\\big|_{\\Omega_r}
    """
    return fields.left, fields.right


@register_method(
    "null_shift",
    "Eq. 3 with the disparity off by controls.null_shift pixels",
    estimator_noise=False,
)
def shifted_pair(fields: AlignedFields):
    """Null warp (:func:`stereovar.controls.null_warps.shifted_warp`)."""
    return fields.left, fields["null_shift"]


@register_method(
    "null_flip", "Eq. 3 with the right variance field flipped upside down", estimator_noise=False
)
def flipped_pair(fields: AlignedFields):
    """Null warp (:func:`stereovar.controls.null_warps.flipped_warp`)."""
    return fields.left, fields["null_flip"]


@register_method(
    "partial",
    "Pearson of ln sigma^2 residuals after a cubic in ln mu, per view and region",
    transform=_partial,
)
def partial_pair(fields: AlignedFields):
    """Intensity-controlled correlation (:func:`stereovar.controls.intensity.partial_pair`)."""
    return fields.left, fields.warped, fields["mean_left"], fields["mean_warped"]


@register_method("relative", "Pearson of the relative variance sigma^2 / mu^2")
def relative_pair(fields: AlignedFields):
    """Relative variance (:func:`stereovar.controls.intensity.relative_variance`).

    .. math::

        \\rho_{\\text{rel}} = \\mathrm{corr}\\bigl(\\sigma_L^2/\\mu_L^2,\\
            \\hat\\sigma_{R\\to L}^2/\\hat\\mu_{R\\to L}^2\\bigr)
    """
    from ..controls.intensity import relative_variance

    return (
        relative_variance(fields.left, fields["mean_left"]),
        relative_variance(fields.warped, fields["mean_warped"]),
    )


@register_method(
    "sensor",
    "Eq. 3 on a Poisson-Gaussian camera's analytic variance a*mu + b",
    estimator_noise=False,
)
def sensor_pair(fields: AlignedFields):
    """Sensor baseline (:func:`stereovar.controls.sensor.sensor_variance`), warped by Eq. 2."""
    return fields["sensor_left"], fields["sensor_warped"]


@register_method(
    "sensor_sim",
    "Eq. 1-3 on N simulated Poisson-Gaussian frames per view",
    estimator_noise=False,
)
def simulated_sensor_pair(fields: AlignedFields):
    """Sensor baseline from frames (:func:`stereovar.controls.sensor.simulated_sensor_variance`)."""
    return fields["sensor_sim_left"], fields["sensor_sim_warped"]
