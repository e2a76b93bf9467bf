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
    and :math:`\\sigma^2/\\mu^2`, which removes albedo but not a camera's
    :math:`a\\mu + b` (the calibration measures 14% false positives above its matched null
    on the default scenes, so it is shown, never used for a verdict).
``sensor``, ``sensor_sim``
    A Poisson-Gaussian camera on the seed mean: its analytic variance field, and Eq. 1
    over :math:`N` simulated frames per view.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..registry import Registry
from .bootstrap import (
    FEWER_THAN_2_TILES,
    bootstrap_replicates,
    draw_counts,
    percentile_interval,
    product_sums,
    standardized_pair,
)
from .correlation import CONSTANT, fisher_interval, undefined_result
from .fields import AlignedFields, AnalysisSettings, MissingField
from .pixels import PixelSet
from .robust import firefly_count, log_floor, products_top_share, ranks, trim_mask

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
    chance : bool
        Report ``chance_se``, the standard error of :math:`\\rho` if the two fields were
        independent (:func:`stereovar.statistics.chance.chance_se`): the chance term of the
        statistic's difference from its matched null.
    """

    pair: Callable[..., tuple]
    description: str
    transform: Callable | None = None
    estimator_noise: bool = True
    curve: bool = False
    chance: bool = False


METHODS = Registry("statistic")
"""Name to :class:`Method`, in the order rows and table columns appear."""

_CHUNK = 1 << 16
"""Pixels per chunk of :func:`pearson_point`'s centred sums (512 KiB of float64)."""

PRIMARY_METHOD = "warp"
"""The statistic Table 1's ``mean_rho`` and Table 2's ``rho_{region}`` report."""


def register_method(
    name: str,
    description: str,
    *,
    transform: Callable | None = None,
    estimator_noise: bool = True,
    curve: bool = False,
    chance: bool = False,
    replace: bool = False,
):
    """Decorator registering ``pair(fields) -> (a, b, ...)`` as statistic ``name``."""

    def decorator(pair):
        METHODS.register(
            name,
            Method(pair, description, transform, estimator_noise, curve, chance),
            replace=replace,
        )
        return pair

    return decorator


def secondary_methods() -> tuple[str, ...]:
    """Every registered statistic but :data:`PRIMARY_METHOD`."""
    return tuple(m for m in METHODS.names() if m != PRIMARY_METHOD)


# ---------------------------------------------------------------- evaluation


class RegionPairs(NamedTuple):
    """The pairs one statistic correlates over one region (:func:`region_values`).

    Attributes
    ----------
    a, b : numpy.ndarray (n,)
        Transformed values (finite).
    selected : numpy.ndarray of int or None
        Positions, among the region's pixels, of the pairs used (None: all of them).
    raw : tuple of numpy.ndarray
        ``a`` and ``b`` before the transform and before it drops any pair (e.g. the
        trimming): the region's finite values.
    kept : numpy.ndarray of int or None
        Positions, among ``raw``, of the pairs the transform kept (None: all of them).
    n_nonfinite : int
        Pixels of the region dropped because a field (or its transform) was not finite.
    """

    a: np.ndarray
    b: np.ndarray
    selected: np.ndarray | None
    raw: tuple
    kept: np.ndarray | None
    n_nonfinite: int


def region_values(arrays, transform, pixels, settings: AnalysisSettings) -> RegionPairs:
    """The transformed pairs of one region and where they come from.

    Parameters
    ----------
    arrays : sequence of array_like (H, W)
        A method's ``pair`` output.
    transform : callable or None
        The method's transform.
    pixels : PixelSet or array_like of bool (H, W)
        The region (:class:`~stereovar.statistics.pixels.PixelSet` shares the gathered
        values between statistics).
    settings : AnalysisSettings

    Returns
    -------
    RegionPairs
    """
    if not isinstance(pixels, PixelSet):
        pixels = PixelSet(pixels)
    values = [pixels.values(f) for f in arrays]
    bad = [pixels.nonfinite(v) for v in values]
    selected = None
    if any(m is not None for m in bad):
        ok = ~np.logical_or.reduce([m for m in bad if m is not None])
        selected = np.flatnonzero(ok)
        values = [v[selected] for v in values]
    n_nonfinite = pixels.size - values[0].size
    raw = (values[0], values[1])
    if transform is None or not values[0].size:
        return RegionPairs(values[0], values[1], selected, raw, None, n_nonfinite)
    out = transform(tuple(values), settings)
    a, b = out[0], out[1]
    finite = np.isfinite(a) & np.isfinite(b)
    n_nonfinite += int(finite.size - np.count_nonzero(finite))
    keep = finite if len(out) < 3 else finite & out[2]
    kept = None
    if not keep.all():
        kept = np.flatnonzero(keep)
        a, b = a[kept], b[kept]
        selected = kept if selected is None else selected[kept]
    return RegionPairs(a, b, selected, raw, kept, n_nonfinite)


def pearson_point(a, b) -> float:
    """Pearson's :math:`\\rho` of two value arrays (NaN when either is constant)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.size < 2:
        return float("nan")
    mean_a, mean_b = a.mean(), b.mean()
    # centred sums chunk by chunk: the deviations stay in cache instead of two more arrays
    # as large as the region (einsum, not BLAS: a threaded BLAS dot stalls when parallel
    # jobs share the cores)
    sab = saa = sbb = 0.0
    for start in range(0, a.size, _CHUNK):
        da = a[start : start + _CHUNK] - mean_a
        db = b[start : start + _CHUNK] - mean_b
        sab += np.einsum("i,i->", da, db)
        saa += np.einsum("i,i->", da, da)
        sbb += np.einsum("i,i->", db, db)
    if not (saa > 0 and sbb > 0):
        return float("nan")
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
    values and :func:`~stereovar.statistics.robust.firefly_count` of the raw ones (the
    region's finite values, before any trimming).

    Parameters
    ----------
    mask : PixelSet or array_like of bool (H, W)
        The region; a :class:`~stereovar.statistics.pixels.PixelSet` built with the tile
        labels replaces ``labels``.

    Returns
    -------
    dict
        The :data:`~stereovar.statistics.correlation.RESULT_KEYS`.
    """
    pixels = mask if isinstance(mask, PixelSet) else PixelSet(mask, labels)
    try:
        a, b, selected, raw, kept, n_nonfinite = region_values(
            method.pair(fields), method.transform, pixels, settings
        )
    except MissingField as missing:
        return undefined_result(0, 0, str(missing))
    n = int(a.size)
    if n < settings.min_pixels:
        return undefined_result(
            n, n_nonfinite, f"fewer than {settings.min_pixels} valid pixels (n={n})"
        )
    da, db = standardized_pair(a, b)
    products = (da * da, db * db, da * db)
    saa, sbb, sab = (float(p.sum()) for p in products)
    if not (saa > 0 and sbb > 0):
        return undefined_result(n, n_nonfinite, CONSTANT)
    rho = float(np.clip(sab / np.sqrt(saa * sbb), -1.0, 1.0))
    result = {
        **undefined_result(n, n_nonfinite, ""),
        "rho": rho,
        **fisher_interval(rho, n),
        "mean_a": float((raw[0] if kept is None else raw[0][kept]).mean()),
        "top_share": products_top_share(products[2]),
        "n_fireflies": firefly_count(
            raw[0],
            raw[1],
            settings.firefly_factor,
            medians=(pixels.median(raw[0]), pixels.median(raw[1])),
        ),
    }
    if method.chance:
        from .chance import chance_se

        where = pixels.index if selected is None else pixels.index[selected]
        result["chance_se"] = chance_se(da, db, where, pixels.shape)
    if pixels.tiles is not None and draws is not None:
        tiles = pixels.tiles if selected is None else pixels.tiles[selected]
        sums = product_sums(tiles, da, db, products)
        result["n_tiles"] = int(sums.shape[0])
        if sums.shape[0] < 2:
            result["reason"] = FEWER_THAN_2_TILES
        else:
            reps = bootstrap_replicates(sums, draws.counts(sums.shape[0]))
            result["boot_low"], result["boot_high"] = percentile_interval(reps)
    return result


def point_rho(method: Method, fields: AlignedFields, mask, settings: AnalysisSettings) -> float:
    """:math:`\\rho` of a statistic alone, without intervals or diagnostics (the seed-subset
    curve); NaN when undefined."""
    try:
        pairs = region_values(method.pair(fields), method.transform, mask, settings)
    except MissingField:
        return float("nan")
    if pairs.a.size < settings.min_pixels:
        return float("nan")
    return pearson_point(pairs.a, pairs.b)


def point_estimate(method: Method, fields_a, fields_b, mask, settings, *, side: int) -> float:
    """:math:`\\rho` between one view's field in two estimates (e.g. the two split halves).

    ``side`` 0 compares the methods' ``a`` fields (left view), 1 the ``b`` fields (right
    view, warped); covariates are taken from the same view.
    """
    try:
        one = method.pair(fields_a)
        two = method.pair(fields_b)
    except MissingField:
        return float("nan")
    covariates = list(one[2:])
    if covariates:
        covariates = [covariates[side]] * 2
    pairs = region_values([one[side], two[side], *covariates], method.transform, mask, settings)
    if pairs.a.size < settings.min_pixels:
        return float("nan")
    return pearson_point(pairs.a, pairs.b)


# ---------------------------------------------------------------- transforms


def _ranked(values, settings):
    return ranks(values[0]), ranks(values[1])


def _logged(values, settings):
    return log_floor(values[0])[0], log_floor(values[1])[0]


def _trimmed(values, settings):
    return values[0], values[1], trim_mask(values[0], values[1], settings.trim_fraction)


def _partial(values, settings):
    from ..controls.partial import partial_pair

    covariates = values[4:]
    half = len(covariates) // 2
    if half == 5 and np.any(np.asarray(covariates[2]) > 0):  # frames stored as integers
        from ..controls.quantisation import FIXED_SHARE, fixed_share

        share = max(fixed_share(values[0], covariates[2]),
                    fixed_share(values[1], covariates[half + 2]))
        if share >= FIXED_SHARE:
            raise MissingField(
                f"the frames' integer encoding fixes the variance at {100 * share:.0f}% of the "
                "pixels (every frame on one code or two neighbouring ones): their Monte Carlo "
                "part cannot be told from the quantisation of their mean"
            )
    e_a, e_b = partial_pair(
        *values[:4], covariates=(covariates[:half], covariates[half:]) if half else None
    )
    if e_a.size and np.isnan(e_a).all() and np.isfinite(values[0]).any():
        from ..controls.intensity import MIN_RESIDUAL_VARIANCE

        raise MissingField(
            f"the control explains ln sigma^2 to within a variance of {MIN_RESIDUAL_VARIANCE:g}: "
            "the field is a function of the seed mean, with nothing left to correlate"
        )
    return e_a, e_b


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
    "Pearson of ln sigma^2 residuals after a spline in ln mu (knots by GCV), chromaticity and "
    "sensor position, per view and region",
    transform=_partial,
    chance=True,
)
def partial_pair(fields: AlignedFields):
    """Intensity-controlled correlation (:func:`stereovar.controls.partial.partial_pair`),
    with each view's chromaticity and sensor position
    (:func:`stereovar.statistics.fields.control_covariates`)."""
    covariates = fields["control_covariates"] if "control_covariates" in fields else ()
    return (fields.left, fields.warped, fields["mean_left"], fields["mean_warped"],
            *covariates)


@register_method("relative", "Pearson of the relative variance sigma^2 / mu^2")
def relative_pair(fields: AlignedFields):
    """Relative variance (:func:`stereovar.controls.intensity.relative_variance`).

    .. math::

        \\rho_{\\text{rel}} = \\mathrm{corr}\\bigl(\\sigma_L^2/\\mu_L^2,\\
            \\hat\\sigma_{R\\to L}^2/\\hat\\mu_{R\\to L}^2\\bigr)
    """
    return fields["relative_left"], fields["relative_warped"]


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
