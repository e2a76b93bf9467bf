"""One scene's correlation rows: every region times every registered statistic (Eq. 3).

The rows are the contract of ``results/{renderer}/{estimator}/correlation/{scene}/spp{spp}.csv``
(:data:`CORRELATION_COLUMNS`); :func:`seed_curve_rows` gives the companion
``.../correlation/{scene}/spp{spp}_curve.csv`` (:data:`CURVE_COLUMNS`): :math:`\\rho` at
:math:`N' < N` seeds from disjoint seed subsets.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..seeding import derive_seed
from .bootstrap import tile_labels
from .correlation import NO_GLASS, RESULT_KEYS, undefined_result
from .fields import (
    AlignedFields,
    AnalysisSettings,
    aligned_fields,
    seed_mean_controls,
    warp_field,
)
from .pixels import PixelSet
from .regions import REGIONS, as_field, region_masks
from .registry import METHODS, BootstrapDraws, evaluate, point_estimate, point_rho
from .reliability import (
    CORRECTED_ABOVE_1,
    TOO_FEW_SEEDS,
    attenuation_corrected,
    curve_summary,
    spearman_brown,
)
from .warp import WarpPlan

RELIABILITY_KEYS = ("reliability_left", "reliability_right", "rho_corrected")

CORRELATION_COLUMNS = [
    "scene",
    "spp",
    "n_seeds",
    "region",
    "method",
    *RESULT_KEYS,
    *RELIABILITY_KEYS,
    "note",
    "renderer",
    "estimator",
]
"""Columns of the per-scene correlation CSV."""

CURVE_COLUMNS = [
    "scene",
    "spp",
    "region",
    "method",
    "n_prime",
    "mean_rho",
    "std_rho",
    "n_subsets",
    "renderer",
    "estimator",
]
"""Columns of the per-scene seed-subset curve CSV."""


@dataclass
class SceneInputs:
    """What the controls need beyond the two variance fields (all optional).

    Attributes
    ----------
    ground_truth_left : mapping
        ``disparity`` and ``valid`` of the left view (null warps, sensor warp).
    sign : int
        ``disparity_sign``.
    mean : dict
        View to the seed mean (H, W, C) (intensity control, sensor baseline).
    halves : dict
        View to the split-half fields (2, H, W) (reliability).
    n_seeds : int
        :math:`N` (sensor frames; the split-half reason).
    sensor : stereovar.controls.sensor.SensorModel
    label : str
        Labels the bootstrap and sensor seeds (the scene and SPP).
    encoding : dict, optional
        How the renders were stored when they were integers (``bits``, ``transfer``,
        ``scale``): the intensity control then removes the variance the encoding implies
        (:mod:`stereovar.controls.quantisation`).
    """

    ground_truth_left: object = None
    sign: int = 1
    mean: dict | None = None
    halves: dict | None = None
    n_seeds: int = 0
    sensor: object = None
    label: str = ""
    encoding: dict | None = None
    notes: dict = field(default_factory=dict)
    _plan: object = field(default=None, repr=False)

    @property
    def plan(self) -> WarpPlan:
        """The Eq. 2 sampling plan of the left ground truth, built once per scene."""
        if self._plan is None:
            gtl = self.ground_truth_left
            self._plan = WarpPlan(
                np.asarray(gtl["disparity"]), sign=self.sign, valid=np.asarray(gtl["valid"])
            )
        return self._plan

    def warp(self, right) -> np.ndarray:
        """:func:`~stereovar.statistics.fields.warp_field` of a right-view field by
        :attr:`plan`."""
        return warp_field(right, self.ground_truth_left, sign=self.sign, plan=self.plan)


def sensor_fields(inputs: SceneInputs) -> dict:
    """The sensor baseline's fields in left coordinates, computed on first use
    (:mod:`stereovar.controls.sensor`); notes the floored :math:`\\mu` entries."""
    from ..controls.sensor import sensor_variance, simulated_sensor_variance

    model = inputs.sensor
    cache = {}

    def analytic(view):
        if view not in cache:
            cache[view], floored = sensor_variance(inputs.mean[view], model)
            if floored:
                inputs.notes[f"mu_floored_{view}"] = floored
        return cache[view]

    def simulated(view, index):
        seed = (int(model.seed), derive_seed("sensor", inputs.label, view), index)
        return simulated_sensor_variance(inputs.mean[view], inputs.n_seeds, model, seed)

    fields = {
        "sensor_left": lambda: analytic("left"),
        "sensor_warped": lambda: inputs.warp(analytic("right")),
    }
    if inputs.n_seeds >= 2:
        fields["sensor_sim_left"] = lambda: simulated("left", 0)
        fields["sensor_sim_warped"] = lambda: inputs.warp(simulated("right", 1))
    return fields


def _fields(left, right, warped, inputs: SceneInputs, settings, controls, sensor=None):
    return aligned_fields(
        left,
        right,
        warped,
        ground_truth_left=inputs.ground_truth_left,
        sign=inputs.sign,
        settings=settings,
        sensor=sensor,
        **(controls or {}),
    )


def correlation_rows(
    sigma_left,
    sigma_right,
    aligned: dict,
    glass,
    *,
    finite_right=None,
    min_pixels: int | None = None,
    settings: AnalysisSettings | None = None,
    inputs: SceneInputs | None = None,
) -> list[dict]:
    """Rows region x statistic from an Eq. 2 alignment (paper Sec. 2.3, 3.1).

    For each region :math:`r` of :data:`~stereovar.statistics.regions.REGIONS` and each
    statistic of :data:`~stereovar.statistics.registry.METHODS` (``warp``: Eq. 3,
    ``no_warp``: Eq. 3 without Eq. 2, the robust statistics and the controls),

    .. math::

        \\rho_{\\text{warp}} = \\mathrm{corr}\\bigl(\\sigma_L^2,\\,
            \\hat\\sigma_{R\\to L}^2\\bigr)\\big|_{\\Omega_r}, \\qquad
        \\rho_{\\text{corrected}} = \\frac{\\rho}{\\sqrt{r_L r_R}},

    with the Fisher-z and block-bootstrap intervals
    (:func:`~stereovar.statistics.registry.evaluate`) and, for statistics of Eq. 1
    estimates, the split-half reliabilities :math:`r_V` stepped up to :math:`N` by
    Spearman-Brown (:mod:`stereovar.statistics.reliability`).

    :math:`\\Omega` is the warp's valid set (ground-truth ``valid``, :math:`d > 0`,
    correspondence inside the right image) further restricted to pixels whose left value is
    finite and whose warped right value is built only from finite right pixels. Every
    statistic uses the same :math:`\\Omega_r` (a control may drop more pixels where its own
    fields are undefined, e.g. a shifted correspondence outside the image).

    Parameters
    ----------
    sigma_left, sigma_right : array_like or xarray.DataArray, shape (H, W)
        :math:`\\sigma_L^2`, :math:`\\sigma_R^2` (Eq. 1).
    aligned : dict
        :func:`stereovar.statistics.warp.align_variance` output (or read back from the
        warped store).
    glass : array_like of bool, shape (H, W)
        The left view's glass mask.
    finite_right : array_like of bool, shape (H, W), optional
        The right variance field's ``finite`` flags.
    min_pixels : int, keyword-only, optional
        Fewest pixels for a defined statistic (overrides ``settings.min_pixels``).
    settings : AnalysisSettings, keyword-only, optional
    inputs : SceneInputs, keyword-only, optional
        Ground truth, seed mean, split halves and sensor model; statistics whose inputs are
        absent get NaN with the reason.

    Returns
    -------
    list of dict
        Rows in the order regions x statistics with ``region``, ``method``, the
        :data:`~stereovar.statistics.correlation.RESULT_KEYS`, ``reliability_left``,
        ``reliability_right``, ``rho_corrected`` and ``note`` (e.g. a corrected
        :math:`\\rho` above 1). ``n_nonfinite`` adds the region's ground-truth-valid pixels
        excluded because a render was NaN or Inf; a scene without glass gives
        ``"no glass pixels in the scene"`` for every glass row.
    """
    settings = settings or AnalysisSettings()
    if min_pixels is not None:
        settings = replace(settings, min_pixels=int(min_pixels))
    if settings.min_pixels < 4:
        raise ValueError(f"min_pixels must be at least 4, got {settings.min_pixels}")
    inputs = inputs or SceneInputs()
    left = as_field(sigma_left).astype(np.float64)
    right = as_field(sigma_right).astype(np.float64)
    glass = as_field(glass).astype(bool)
    masks = region_masks({"glass": glass}, as_field(aligned["omega"]).astype(bool))
    gt_masks = region_masks({"glass": glass}, as_field(aligned["omega_geometry"]).astype(bool))
    usable = as_field(aligned["usable"]).astype(bool)
    fin_right = np.isfinite(right)
    if finite_right is not None:
        fin_right &= as_field(finite_right).astype(bool)
    right = np.where(fin_right, right, np.nan)
    warped = as_field(aligned["warped"]).astype(np.float64)
    controls = None
    sensor = None
    if inputs.mean is not None and inputs.ground_truth_left is not None:
        controls = seed_mean_controls(
            inputs.mean["left"], inputs.mean["right"], inputs.ground_truth_left,
            sign=inputs.sign, plan=inputs.plan, encoding=inputs.encoding,
        )
        if inputs.sensor is not None:
            sensor = sensor_fields(inputs)
    fields = _fields(left, right, warped, inputs, settings, controls, sensor)
    halves = None
    if inputs.halves is not None and inputs.ground_truth_left is not None:
        halves = [
            _fields(
                as_field(inputs.halves["left"][h]).astype(np.float64),
                as_field(inputs.halves["right"][h]).astype(np.float64),
                inputs.warp(inputs.halves["right"][h]),
                inputs,
                settings,
                controls,
            )
            for h in range(2)
        ]
    labels = tile_labels(left.shape, settings.bootstrap.tile)
    has_glass = bool(glass.any())
    rows = []
    for region in REGIONS:
        excluded = int((gt_masks[region] & ~usable).sum())
        draws = BootstrapDraws(
            settings.bootstrap, derive_seed(settings.bootstrap.seed, inputs.label, region)
        )
        pixels = PixelSet(masks[region], labels)
        for name, method in METHODS.items():
            if region == "glass" and not has_glass:
                result = undefined_result(0, 0, NO_GLASS)
            else:
                result = evaluate(method, fields, pixels, settings=settings, draws=draws)
                result["n_nonfinite"] += excluded
            row = {"region": region, "method": name, **result}
            row.update(_reliability(method, halves, pixels, settings, row, inputs))
            rows.append(row)
    floored = {k: v for k, v in inputs.notes.items() if k.startswith("mu_floored")}
    if floored:
        text = "mu <= 0 floored at 0: " + ", ".join(
            f"{k.rsplit('_', 1)[1]} {v}" for k, v in floored.items()
        )
        for row in rows:
            if row["method"].startswith("sensor"):
                row["note"] = "; ".join(n for n in (row["note"], text) if n)
    return rows


def _reliability(method, halves, mask, settings, row, inputs) -> dict:
    nan = float("nan")
    out = {"reliability_left": nan, "reliability_right": nan, "rho_corrected": nan, "note": ""}
    if not method.estimator_noise or not np.isfinite(row["rho"]):
        return out
    if halves is None:
        if inputs.halves is None and inputs.n_seeds and inputs.n_seeds < 4:
            out["note"] = TOO_FEW_SEEDS
        return out
    r_left = point_estimate(method, halves[0], halves[1], mask, settings, side=0)
    r_right = point_estimate(method, halves[0], halves[1], mask, settings, side=1)
    out["reliability_left"] = spearman_brown(r_left)
    out["reliability_right"] = spearman_brown(r_right)
    corrected, above = attenuation_corrected(
        row["rho"], out["reliability_left"], out["reliability_right"]
    )
    out["rho_corrected"] = corrected
    if above:
        out["note"] = CORRECTED_ABOVE_1
    return out


def subset_rhos(subsets: dict, aligned: dict, glass, *, settings=None, inputs=None) -> dict:
    """:math:`\\rho` of every ``curve=True`` statistic on every disjoint seed subset.

    .. math:: \\rho^{(i)}_{N'} = \\mathrm{corr}\\bigl(\\sigma^{2\\,(i)}_{L,N'},\\,
        \\hat\\sigma^{2\\,(i)}_{R\\to L,N'}\\bigr)\\big|_{\\Omega_r}

    Parameters
    ----------
    subsets, aligned, glass, settings, inputs
        As in :func:`seed_curve_rows`.

    Returns
    -------
    dict
        ``(region, method, N')`` to the list of :math:`\\rho` over the subsets of size
        :math:`N'`, in subset order.
    """
    settings = settings or AnalysisSettings()
    inputs = inputs or SceneInputs()
    values: dict = {}
    if not subsets or inputs.ground_truth_left is None:
        return values
    glass = as_field(glass).astype(bool)
    masks = region_masks({"glass": glass}, as_field(aligned["omega"]).astype(bool))
    curve_methods = [(n, m) for n, m in METHODS.items() if m.curve]
    sizes, _, left_stack = subsets["left"]
    right_stack = subsets["right"][2]
    omega = PixelSet(masks["all"])
    regions = [
        (r, omega if r == "all" else PixelSet(masks[r], parent=omega))
        for r in REGIONS
        if masks[r].any()
    ]
    for k, size in enumerate(sizes):
        right = np.asarray(right_stack[k])
        fields = AlignedFields(np.asarray(left_stack[k]), inputs.plan.field(right), right)
        for region, pixels in regions:
            for name, method in curve_methods:
                rho = point_rho(method, fields, pixels, settings)
                values.setdefault((region, name, int(size)), []).append(rho)
        for _, pixels in regions:  # each subset's fields are read once
            pixels.forget()
    return values


def seed_curve_rows(
    subsets: dict,
    aligned: dict,
    glass,
    rows: list[dict],
    *,
    n_seeds: int,
    settings=None,
    inputs: SceneInputs | None = None,
    values: dict | None = None,
) -> list[dict]:
    """:math:`\\rho` against the number of seeds, from disjoint seed subsets.

    For each subset size :math:`N'` (:mod:`stereovar.estimators.subsets`), region and
    statistic with ``curve=True``, the mean and sample standard deviation over the
    :math:`\\lfloor N/N' \\rfloor` disjoint subsets of :math:`\\rho^{(i)}_{N'}`
    (:func:`subset_rhos`), and the full estimate's :math:`\\rho` (one "subset",
    :math:`N' = N`) from ``rows``.

    Parameters
    ----------
    subsets : dict
        View to ``(sizes, indices, fields)``: the variance store's ``subset_variance``
        (fields (S, H, W)) with its ``subset_size`` and ``subset_index``.
    aligned, glass
        As in :func:`correlation_rows`.
    rows : list of dict
        :func:`correlation_rows` of the full estimate.
    n_seeds : int
    settings : AnalysisSettings, optional
    inputs : SceneInputs, optional
        Its ground truth warps the subsets' right fields.
    values : dict, optional
        :func:`subset_rhos` when already computed (e.g. beside the correlation rows).

    Returns
    -------
    list of dict
        ``region``, ``method``, ``n_prime``, ``mean_rho``, ``std_rho``, ``n_subsets``.
    """
    if values is None:
        values = subset_rhos(subsets, aligned, glass, settings=settings, inputs=inputs)
    curve_methods = [n for n, m in METHODS.items() if m.curve]
    out = []
    for region in REGIONS:
        for name in curve_methods:
            sizes_here = sorted(s for (r, m, s) in values if (r, m) == (region, name))
            for size in sizes_here:
                out.append(
                    {
                        "region": region,
                        "method": name,
                        "n_prime": size,
                        **curve_summary(values[(region, name, size)]),
                    }
                )
            full = [r["rho"] for r in rows if (r["region"], r["method"]) == (region, name)]
            out.append(
                {"region": region, "method": name, "n_prime": int(n_seeds), **curve_summary(full)}
            )
    return out
