"""One scene's calibration replicates: synthetic frames through every transform and statistic.

For each replicate :math:`r` and each design (a matched null, or the planted cue at one
strength; :mod:`stereovar.calibration.synthesis`), :math:`N` frames per view are drawn around
the scene's seed means at the renders' camera law (:mod:`stereovar.calibration.law`), passed
through each transform of the run exactly as the renders are
(:mod:`stereovar.calibration.stacks`: the seed mean and variance over the :math:`N` frames),
and measured by the same Eq. 1, Eq. 2 and every registered statistic with its
block-bootstrap interval (:mod:`stereovar.calibration.view_statistics`). The camera
pipelines' nulls follow (:func:`pipeline_rows`). Nothing is rendered.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..intervention.lift import LIFT_METHOD
from ..seeding import derive_seed
from .law import camera_residual_variance, render_strength, scene_law
from .pipelines import (
    GAIN_MAP_SCALE,
    GAIN_MAP_SD,
    PIPELINES,
    dequantised_mean,
    draw_pipeline,
    encoded_clean,
    encoded_frames,
    integer_roundtrip,
    pipeline_encoding,
)
from .scene_frames import SceneFrames
from .stacks import NONE
from .synthesis import (
    NULL_KINDS,
    camera_law,
    draw_frames,
    planted_pattern,
    smooth_field,
    variance_fields,
)
from .view_statistics import (
    CALIBRATED_METHODS,
    CLAIM_CONTROL,
    SHARED_STREAMS_METHOD,
    measured_rows,
)

TRANSFORM_MIN_FACTOR = 0.25
"""The weakest planted strength passed through a transform: the finer strengths, which set
the instrument's smallest detectable effect, run untransformed only."""

CALIBRATION_COLUMNS = [
    "scene",
    "replicate",
    "kind",
    "strength",
    "strength_factor",
    "transform",
    "region",
    "method",
    "rho",
    "boot_low",
    "boot_high",
    "chance_se",
    "n_pixels",
    "null_kind",
]
"""Columns of one scene's replicate rows (``results/.../calibration/{scene}/spp{spp}.csv``);
``null_kind``: the design whose replicates are the row's matched null (``camera``, or the
camera law through an 8-bit pipeline's encoding, ``camera_srgb8_<q>``)."""

PIPELINE_METHODS = ("partial", SHARED_STREAMS_METHOD, LIFT_METHOD, "warp", "sensor_sim")
"""The statistics the pipeline nulls measure: the verdict's, the shared-streams check, the
variance-matching cost's lift (the matching-cue rule's) and the claims table's level claim
with its camera baseline."""

NULL_METHODS = (*CALIBRATED_METHODS, SHARED_STREAMS_METHOD, LIFT_METHOD, CLAIM_CONTROL)
"""The statistics the cue-free designs measure as drawn: every calibrated one, both checks
of the audit's light and the claims table's camera baseline."""


def designs(strength_factors, render_s: float) -> list[tuple[str, float, float]]:
    """``(kind, strength, strength_factor)`` of every design: the nulls, then the planted cue
    at each factor times the renders' strength ``render_s``."""
    out = [(k, 0.0, 0.0) for k in NULL_KINDS]
    out += [("planted", float(f) * render_s, float(f)) for f in strength_factors]
    return out


def scene_calibration(
    scene: SceneFrames,
    *,
    transforms,
    settings,
    replicates: int,
    strength_factors,
    expensive_replicates: int,
    expensive: frozenset = frozenset(),
    options: dict | None = None,
    seed: int = 0,
    min_strength: float = 0.05,
    pipelines=(),
    pipeline_replicates: int = 0,
    methods=None,
) -> tuple[list[dict], dict]:
    """Every replicate of one scene.

    Parameters
    ----------
    scene : SceneFrames
    transforms : sequence of str
        :data:`~stereovar.calibration.stacks.NONE` and the run's store transforms.
    settings : stereovar.statistics.fields.AnalysisSettings
        The run's analysis settings (bootstrap tile, replicates and seed).
    replicates : int
        Replicates of every design.
    strength_factors : sequence of float
        The planted strengths, as multiples of what the renders show
        (:func:`~stereovar.calibration.law.render_strength`); a transform sees those from
        :data:`TRANSFORM_MIN_FACTOR` up.
    expensive_replicates : int
        Replicates of the transforms in ``expensive`` (the denoisers), which see the nulls
        and the planted cue from :data:`TRANSFORM_MIN_FACTOR` up, as the cheap ones do.
    options : dict, optional
        Transform name to its keyword options (the run's camera).
    seed : int
        Seeds every draw with the scene label.
    min_strength : float
        The renders' strength used when they show less (so the planted grid is not all 0).
    pipelines : sequence of str
        Pipeline nulls (:data:`~stereovar.calibration.pipelines.PIPELINES`) drawn
        ``pipeline_replicates`` times each (:func:`pipeline_rows`).
    pipeline_replicates : int
    methods : sequence of str, optional
        The statistics every design measures (default: the light's checks through ``none``,
        :data:`~stereovar.calibration.view_statistics.CALIBRATED_METHODS`
        through the transforms).

    Returns
    -------
    rows : list of dict
        :data:`CALIBRATION_COLUMNS` (``scene`` left for the caller).
    info : dict
        ``camera_law`` (a, b), ``render_strength``, ``replicates`` and
        ``expensive_replicates``.
    """
    law, clean = scene_law(scene, seed)
    options = dict(options or {})
    rows: list[dict] = []
    render_s = None
    for r in range(int(replicates)):
        rng = np.random.default_rng(derive_seed("calibration", seed, scene.label, r))
        gt_r = scene.ground_truth["right"]
        pattern = planted_pattern(gt_r["disparity"], gt_r["valid"], sign=scene.sign, rng=rng)
        if render_s is None:
            noise_var = camera_residual_variance(scene, law, rng)
            render_s = max(render_strength(scene, settings, noise_var), min_strength)
        for kind, strength, factor in designs(strength_factors, render_s):
            # the denoisers see the nulls and the planted series from TRANSFORM_MIN_FACTOR,
            # so that their own power curve sets their margin
            cheap_only = r >= expensive_replicates
            cache = {}
            chosen = [
                t
                for t in transforms
                if not (cheap_only and t in expensive)
                and (t == NONE or kind != "planted" or factor >= TRANSFORM_MIN_FACTOR)
            ]
            if not chosen:
                continue
            v = variance_fields(
                kind,
                strength,
                mean=clean,
                law=law,
                render_variance=scene.variance,
                pattern=pattern,
                rng=rng,
            )
            frames = {
                view: encoded_frames(draw_frames(clean[view], v[view], scene.n_seeds, rng,
                                                 channel_correlation=scene.channel_correlation),
                                     scene.encoding)
                for view in ("left", "right")
            }
            for name in chosen:
                design = {"replicate": r, "kind": kind, "strength": strength,
                          "strength_factor": factor}
                checks = methods
                if name == NONE and methods is None:  # the light's checks as drawn
                    checks = NULL_METHODS if kind in NULL_KINDS else (
                        *CALIBRATED_METHODS, LIFT_METHOD, CLAIM_CONTROL)
                rows += measured_rows(
                    frames, name, scene, settings,
                    label=f"{scene.label}|{r}|{kind}|{factor:g}|{name}",
                    seed=derive_seed("calibration-transform", seed, scene.label, r, kind,
                                     factor, name),
                    options=options.get(name), design=design, methods=checks, cache=cache,
                )
    rows += pipeline_rows(scene, law, settings, replicates=int(pipeline_replicates),
                          pipelines=pipelines, seed=seed)
    info = {
        "camera_law": law,
        "render_strength": render_s,
        "replicates": int(replicates),
        "expensive_replicates": int(min(expensive_replicates, replicates)),
        "pipeline_replicates": int(pipeline_replicates) if pipelines else 0,
    }
    return rows, info


def pipeline_rows(scene: SceneFrames, law, settings, *, replicates: int, pipelines=PIPELINES,
                  seed: int = 0) -> list[dict]:
    """The pipeline nulls of one scene: :data:`PIPELINE_METHODS` on ``replicates`` draws of
    each pipeline (:func:`~stereovar.calibration.pipelines.draw_pipeline`), as shipped
    (transform ``none``).

    A float pipeline is read against the scene's ``camera`` null. An 8-bit one gets its own
    matched null, drawn as an audit of such data draws it: the camera law before the encoding
    (:func:`~stereovar.calibration.pipelines.encoded_law`, from the pipeline's first draw)
    around that draw's seed means, through the same encoding (kind ``camera_<pipeline>``).
    """
    from ..estimators.seeds import variance_field

    rows: list[dict] = []
    views = ("left", "right")
    shape = scene.mean["left"].shape[:2]
    gain_map = np.exp(GAIN_MAP_SD * smooth_field(
        shape, np.random.default_rng(derive_seed("calibration-gain-map", seed, scene.label)),
        scale=GAIN_MAP_SCALE))
    for name in pipelines:
        encoding = pipeline_encoding(name, scene.mean)
        null_kind = "camera" if encoding is None else f"camera_{name}"
        # measured as an audit of such frames measures them: knowing their encoding
        stored = scene if encoding is None else dataclasses.replace(scene, encoding=encoding)
        null_law = data_mean = None
        for r in range(int(replicates)):
            rng = np.random.default_rng(derive_seed("calibration-pipeline", seed, scene.label,
                                                    name, r))
            frames = draw_pipeline(name, scene.mean, law, scene.n_seeds, rng, gain_map)
            designs_here = [(name, frames)]
            if encoding is not None:
                if null_law is None:
                    data_mean, data_var = zip(*(variance_field(frames[v]) for v in views),
                                              strict=True)
                    mu = data_mean[0].mean(axis=-1)
                    fitted = camera_law(data_var[0], mu, scene.ground_truth["left"]["valid"])
                    null_law, _ = encoded_clean(data_mean[0], data_var[0], fitted,
                                                scene.n_seeds, rng, encoding)
                    data_mean = {v: dequantised_mean(m, null_law, encoding, scene.n_seeds)
                                 for v, m in zip(views, data_mean, strict=True)}
                a, b = null_law
                null = {v: integer_roundtrip(draw_frames(
                    data_mean[v], a * np.maximum(data_mean[v], 0.0) + b, scene.n_seeds, rng),
                    **encoding) for v in views}
                designs_here.append((null_kind, null))
            for kind, stacks in designs_here:
                rows += measured_rows(
                    stacks, NONE, stored, settings,
                    label=f"{scene.label}|{r}|{kind}|pipeline",
                    seed=derive_seed("calibration-pipeline-transform", seed, scene.label, r,
                                     kind),
                    design={"replicate": r, "kind": kind, "strength": 0.0,
                            "strength_factor": 0.0, "null_kind": null_kind},
                    methods=PIPELINE_METHODS,
                )
    return rows
