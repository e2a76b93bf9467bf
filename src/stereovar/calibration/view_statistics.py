"""The statistics on one view pair of frame stacks, as rows of one scene's calibration.

The stacks are measured by the same Eq. 1, Eq. 2 and every registered statistic with its
block-bootstrap interval as the renders are (:func:`statistic_rows`,
:func:`stereovar.statistics.rows.correlation_rows`), with the audit's shared-streams check,
the variance-matching cost's lift and the claims table's camera baseline beside them;
:func:`measured_rows` passes the stacks through a transform first
(:mod:`stereovar.calibration.stacks`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..intervention.lift import LIFT_METHOD
from ..seeding import derive_seed
from .scene_frames import SceneFrames
from .stacks import (
    SHIPPED,
    output_encoding_of,
    reads_seed_mean,
    seed_groups,
    shipped_stack,
    transform_stack,
)

CALIBRATED_METHODS = ("warp", "log", "spearman", "partial", "relative", "null_shift")
"""The statistics every replicate measures (over all valid pixels): the paper's Eq. 3, its
robust versions, the intensity controls and a wrong alignment. The camera baselines are left
out: they draw their own frames from the seed mean, and the calibration's ``camera`` null
is that baseline."""

SHARED_STREAMS_METHOD = "shared_streams"
"""The audit's shared-streams check, measured on the cue-free designs as the calibration's
``method`` of that name: its ``rho`` is the per-seed residuals' cross-view correlation at
zero disparity (:func:`_shared_streams_row`)."""

CLAIM_CONTROL = "sensor_sim"
"""The camera baseline the claims table reads a level claim against (its ``rho_all``):
measured on the designs as drawn, so that the claims' rule is calibrated too
(:mod:`stereovar.calibration.claims`)."""


def statistic_rows(
    stacks: dict, scene: SceneFrames, settings, label: str, *, methods=None
) -> list[dict]:
    """Eq. 1, Eq. 2 and each calibrated statistic over all valid pixels, on one view pair of
    frame stacks, by the same functions as the correlation rows
    (:func:`stereovar.statistics.registry.evaluate` with its block bootstrap; the region
    ``all`` of :func:`stereovar.statistics.rows.correlation_rows`).

    Parameters
    ----------
    methods : sequence of str, optional
        Registered statistics (default :data:`CALIBRATED_METHODS`).
    """
    from ..estimators.seeds import variance_field
    from ..seeding import derive_seed as seed_of
    from ..statistics.bootstrap import tile_labels
    from ..statistics.fields import aligned_fields, seed_mean_controls
    from ..statistics.pixels import PixelSet
    from ..statistics.registry import METHODS, BootstrapDraws, evaluate
    from ..statistics.warp import align_variance

    means, fields = {}, {}
    for view, stack in stacks.items():
        means[view], fields[view] = variance_field(np.asarray(stack))
    gt_left = scene.ground_truth["left"]
    aligned = align_variance(
        fields["left"],
        fields["right"],
        gt_left,
        sign=scene.sign,
        finite_left=np.isfinite(fields["left"]),
        finite_right=np.isfinite(fields["right"]),
    )
    right = np.where(np.isfinite(fields["right"]), fields["right"], np.nan)
    sensor = _sensor_fields(means, scene, label) if CLAIM_CONTROL in (methods or ()) else None
    aligned_set = aligned_fields(
        fields["left"], right, aligned["warped"], ground_truth_left=gt_left, sign=scene.sign,
        settings=settings, sensor=sensor,
        **seed_mean_controls(means["left"], means["right"], gt_left, sign=scene.sign,
                             encoding=scene.encoding),
    )
    pixels = PixelSet(
        np.asarray(aligned["omega"], dtype=bool),
        tile_labels(fields["left"].shape, settings.bootstrap.tile),
    )
    draws = BootstrapDraws(settings.bootstrap, seed_of(settings.bootstrap.seed, label, "all"))
    rows = []
    for name in methods or CALIBRATED_METHODS:
        if name == SHARED_STREAMS_METHOD:
            rows.append(_shared_streams_row(stacks, scene, settings))
            continue
        if name == LIFT_METHOD:
            rows.append(_lift_row(fields, scene, settings, seed_of(
                settings.bootstrap.seed, label, LIFT_METHOD)))
            continue
        result = evaluate(METHODS.get(name), aligned_set, pixels, settings=settings, draws=draws)
        rows.append({"region": "all", "method": name, **result})
    return rows


def _shared_streams_row(stacks, scene: SceneFrames, settings) -> dict:
    """The audit's shared-streams check on one view pair of frame stacks: the per-seed
    residuals' cross-view correlation at zero disparity over the valid set
    (:func:`stereovar.statistics.residuals.residual_correlation`), frame :math:`n` of the
    left view with frame :math:`n` of the right."""
    from ..statistics.regions import valid_set
    from ..statistics.residuals import residual_correlation

    gt = scene.ground_truth["left"]
    disparity = np.asarray(gt["disparity"], dtype=np.float64)
    valid = np.asarray(gt["valid"], dtype=bool)
    (row,) = residual_correlation(
        np.asarray(stacks["left"]), np.asarray(stacks["right"]), disparity, sign=scene.sign,
        masks={"all": valid_set(disparity, sign=scene.sign, valid=valid)}, valid=valid,
        alignments=("zero",), settings=settings.bootstrap, min_pixels=settings.min_pixels,
    )
    return {"region": "all", "method": SHARED_STREAMS_METHOD, "rho": row["rho"],
            "boot_low": row["low"], "boot_high": row["high"], "chance_se": float("nan"),
            "n_pixels": row["n_pixels"]}


def _sensor_fields(means, scene: SceneFrames, label: str) -> dict:
    """The ``sensor_sim`` baseline's fields: :math:`N` Poisson-Gaussian frames of the run's
    camera per view around the replicate's own seed means, as the correlation rows draw them
    around the renders' (:func:`stereovar.statistics.rows.sensor_fields`)."""
    from ..controls.sensor import SensorModel
    from ..statistics.rows import SceneInputs, sensor_fields

    inputs = SceneInputs(ground_truth_left=scene.ground_truth["left"], sign=scene.sign,
                         mean=means, n_seeds=scene.n_seeds,
                         sensor=scene.sensor or SensorModel(), label=label)
    return sensor_fields(inputs)


def _lift_row(fields, scene: SceneFrames, settings, seed) -> dict:
    """The variance-matching cost's lift over chance on one view pair's Eq. 1 fields, each in
    its own view's coordinates (:func:`stereovar.intervention.lift.wta_lift`)."""
    from ..intervention.lift import wta_lift

    b = settings.bootstrap
    r = wta_lift(fields["left"], fields["right"], scene.ground_truth["left"], sign=scene.sign,
                 max_disparity=scene.max_disparity, window=scene.window, tile=b.tile,
                 reps=b.reps, seed=seed)
    return {"region": "all", "method": LIFT_METHOD, "rho": r["value"], "boot_low": r["low"],
            "boot_high": r["high"], "chance_se": float("nan"), "n_pixels": r["n_pixels"]}


def measured_rows(
    frames, name, scene, settings, *, label, seed, options=None, design=None, shipped_only=False,
    methods=None, cache=None,
):
    """:data:`~stereovar.calibration.replicates.CALIBRATION_COLUMNS` rows (but ``scene``)
    of one view pair of frame stacks through transform ``name``: as the transform job applies
    it (unless ``shipped_only``), and, for a transform that reads the seed mean, also on what
    it ships (:func:`~stereovar.calibration.stacks.shipped_stack`, labelled ``name`` +
    :data:`~stereovar.calibration.stacks.SHIPPED`).

    ``cache`` (a dict kept over the transforms of one set of frames) holds each transform's
    outputs per view, so that a chain ``a+b`` applies only ``b`` to the outputs ``a`` already
    gave (the denoiser runs once for a generator's denoised and shipped nulls)."""

    def through(name, frames, *, view, seed, aux=None, options=None):
        if cache is None:
            return transform_stack(name, frames, view=view, seed=seed, aux=aux, options=options)
        from ..transforms import CHAIN

        if (name, view) not in cache:
            prefix, _, last = name.rpartition(CHAIN)
            if prefix and (prefix, view) in cache:
                cache[name, view] = transform_stack(last, cache[prefix, view], view=view,
                                                    seed=derive_seed(seed, last), aux=aux)
            else:
                cache[name, view] = transform_stack(name, frames, view=view, seed=seed,
                                                    aux=aux, options=options)
        return cache[name, view]

    paths = [] if shipped_only else [(name, through)]
    if reads_seed_mean(name) and seed_groups(scene.n_seeds):
        paths.append((name + SHIPPED, shipped_stack))
    encoding = output_encoding_of(name)
    if encoding:  # the statistics read the transform's integer output as an audit would
        scene = dataclasses.replace(scene, encoding=encoding)
    rows = []
    for label_name, apply in paths:
        stacks = {
            view: apply(name, frames[view], view=view, seed=derive_seed(seed, view),
                        aux=(scene.aux or {}).get(view), options=options)
            for view in ("left", "right")
        }
        for row in statistic_rows(stacks, scene, settings, f"{label}|{label_name}",
                                  methods=methods):
            rows.append(
                {
                    "null_kind": "camera",
                    **dict(design or {}),
                    "transform": label_name,
                    "region": row["region"],
                    "method": row["method"],
                    "rho": row["rho"],
                    "boot_low": row["boot_low"],
                    "boot_high": row["boot_high"],
                    "chance_se": row["chance_se"],
                    "n_pixels": row["n_pixels"],
                }
            )
    return rows
