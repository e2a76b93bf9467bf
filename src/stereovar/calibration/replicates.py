"""One scene's calibration replicates: synthetic frames through every transform and statistic.

For each replicate :math:`r` and each design (a matched null, or the planted cue at one
strength; :mod:`stereovar.calibration.synthesis`), :math:`N` frames per view are drawn around
the scene's seed means, passed through each transform of the run exactly as the renders are
(:mod:`stereovar.transforms`, the seed mean and variance over the :math:`N` frames), and
measured by the same Eq. 1, Eq. 2 and every registered statistic with its block-bootstrap
interval (:func:`stereovar.statistics.rows.correlation_rows`). Nothing is rendered.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..intervention.lift import LIFT_METHOD
from ..seeding import derive_seed
from .pipelines import (
    GAIN_MAP_SCALE,
    GAIN_MAP_SD,
    PIPELINES,
    dequantised_mean,
    draw_pipeline,
    encoded_clean,
    integer_roundtrip,
    pipeline_encoding,
)
from .synthesis import (
    NULL_KINDS,
    camera_law,
    draw_frames,
    planted_pattern,
    smooth_field,
    variance_fields,
)

NONE = "none"
"""The identity transform: the statistics on the synthetic frames as drawn."""

SHIPPED = "|shipped"
"""Suffix of a transform's label when it is measured on what ships (:func:`shipped_stack`)."""

TRANSFORM_MIN_FACTOR = 0.25
"""The weakest planted strength passed through a transform: the finer strengths, which set
the instrument's smallest detectable effect, run untransformed only."""

CALIBRATED_METHODS = ("warp", "log", "spearman", "partial", "relative", "null_shift")
"""The statistics every replicate measures (over all valid pixels): the paper's Eq. 3, its
robust versions, the intensity controls and a wrong alignment. The camera baselines are left
out: they draw their own frames from the seed mean, and the calibration's ``camera`` null
is that baseline."""

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

QUANTISED_SHARE = "quantised_share"
"""The ``method`` of a shipped output's row whose ``rho`` is the share of valid pixels whose
Eq. 1 variance the output's integer encoding fixes
(:func:`stereovar.controls.quantisation.fixed_share`, the larger of the two views)."""

SHARED_STREAMS_METHOD = "shared_streams"
"""The audit's shared-streams check, measured on the cue-free designs as the calibration's
``method`` of that name: its ``rho`` is the per-seed residuals' cross-view correlation at
zero disparity (:func:`_shared_streams_row`)."""

PIPELINE_METHODS = ("partial", SHARED_STREAMS_METHOD, LIFT_METHOD, "warp", "sensor_sim")
"""The statistics the pipeline nulls measure: the verdict's, the shared-streams check, the
variance-matching cost's lift (the matching-cue rule's) and the claims table's level claim
with its camera baseline."""

CLAIM_CONTROL = "sensor_sim"
"""The camera baseline the claims table reads a level claim against (its ``rho_all``):
measured on the designs as drawn, so that the claims' rule is calibrated too
(:mod:`stereovar.calibration.claims`)."""

NULL_METHODS = (*CALIBRATED_METHODS, SHARED_STREAMS_METHOD, LIFT_METHOD, CLAIM_CONTROL)
"""The statistics the cue-free designs measure as drawn: every calibrated one, both checks
of the audit's light and the claims table's camera baseline."""


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


def transform_stack(
    name: str, frames, *, view: str, seed: int, aux=None, options=None, first_only=False
):
    """The run's transform ``name`` on each of :math:`N` frames of one view, as the
    transform job applies it to renders: every frame sees the seed mean and unbiased
    variance over all :math:`N` (:func:`stereovar.jobs.mitigations.seed_moments`'s
    definition), the view's auxiliary passes when given, and its own random seed.

    A chain ``a+b`` (:func:`stereovar.transforms.transform_chain`) applies each link to
    the previous link's :math:`N` outputs, as a store transform of a store transform would.

    Returns
    -------
    numpy.ndarray (N, H, W, C), float32
        Only the first frame's output (1, H, W, C) with ``first_only``.
    """
    if name == NONE:
        return frames
    from ..transforms import CHAIN, TransformInputs, get_transform

    if CHAIN in name:
        *links, last = name.split(CHAIN)
        for link in links:
            frames = transform_stack(link, frames, view=view, seed=derive_seed(seed, link),
                                     aux=aux, options=(options or {}).get(link))
        return transform_stack(last, frames, view=view, seed=derive_seed(seed, last), aux=aux,
                               options=(options or {}).get(last), first_only=first_only)
    t = get_transform(name)
    stack = np.asarray(frames, dtype=np.float64)
    mean = stack.mean(axis=0)
    var = stack.var(axis=0, ddof=1)
    extra = dict(aux or {})
    out = []
    for i, frame in enumerate(frames[:1] if first_only else frames):
        inputs = TransformInputs(
            render=np.asarray(frame, dtype=np.float32),
            view=view,
            seed_index=i,
            rng_seed=derive_seed(seed, view, i),
            seed_mean=mean,
            seed_var=var,
            n_seeds=len(frames),
            **extra,
        )
        out.append(t(inputs, **dict(options or {})))
    return np.stack(out)


def reads_seed_mean(name: str) -> bool:
    """Whether transform ``name`` builds its images from the seed statistics, so that Eq. 1
    over its :math:`N` outputs cannot see the Monte Carlo noise left in the seed mean."""
    if name == NONE:
        return False
    from ..transforms import transform_chain

    return any({"seed_mean", "seed_var"} & set(t.reads) for t in transform_chain(name))


def output_encoding_of(name: str) -> dict | None:
    """The integer encoding the last link of transform ``name`` writes (a generator's PNG,
    :mod:`stereovar.transforms.output`), or None for a float output."""
    if name == NONE:
        return None
    from ..transforms import transform_chain

    return transform_chain(name)[-1].encoding


def seed_groups(n: int, size: int = 2) -> list[np.ndarray]:
    """Disjoint groups of ``size`` consecutive seed indices among ``n`` (the last takes the
    rest); at least two groups, or none when :math:`n < 2\\,\\text{size}`.

    Examples
    --------
    >>> [g.tolist() for g in seed_groups(8)]
    [[0, 1], [2, 3], [4, 5], [6, 7]]
    >>> [g.tolist() for g in seed_groups(5)]
    [[0, 1], [2, 3, 4]]
    """
    count = n // size
    if count < 2:
        return []
    return np.array_split(np.arange(count * size), count)[:-1] + [
        np.arange((count - 1) * size, n)
    ]


def shipped_stack(name: str, frames, *, view: str, seed: int, aux=None, options=None, size=2):
    """What a transform that reads the seed mean ships, over independent repetitions.

    The :math:`N` frames are split into :math:`G = \\lfloor N/k \\rfloor` disjoint groups of
    :math:`k` (``size``, :func:`seed_groups`); each group is transformed with its own seed
    mean :math:`\\bar I_g` and variance, and its first image kept, so the :math:`G` images
    are independent repetitions of the shipped image:

    .. math::

        I'_g = T\\bigl(I^{(n_g)};\\ \\bar I_g, \\hat\\sigma^2_g\\bigr), \\qquad
        \\operatorname{Var}_g[I'_g] = \\operatorname{Var}[\\bar I_g] + \\text{camera}
            = \\frac{\\sigma^2}{k} + a\\mu + b

    and Eq. 1 over them sees the Monte Carlo noise the seed mean carries
    (:math:`\\sigma^2/k` here, :math:`\\sigma^2/N` in the images a team ships, so the remnant
    is shown :math:`N/k` times stronger relative to the camera noise than it ships).

    Returns
    -------
    numpy.ndarray (G, H, W, C), float32
        Empty (G = 0) when :math:`N < 2k`.
    """
    groups = seed_groups(len(frames), size)
    images = [
        transform_stack(
            name, np.asarray(frames)[g], view=view, seed=derive_seed(seed, "group", i),
            aux=aux, options=options, first_only=True,
        )[0]
        for i, g in enumerate(groups)
    ]
    return np.stack(images) if images else np.empty((0, *np.shape(frames)[1:]), np.float32)


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
    """:data:`CALIBRATION_COLUMNS` rows (but ``scene``) of one view pair of frame stacks
    through transform ``name``: as the transform job applies it (unless ``shipped_only``),
    and, for a transform that reads the seed mean, also on what it ships
    (:func:`shipped_stack`, labelled ``name`` + :data:`SHIPPED`).

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


def renders_shipped_rows(renders: dict, scene: SceneFrames, *, transforms, settings,
                         options=None, seed: int = 0) -> list[dict]:
    """What each transform that reads the seed mean ships, measured on the run's own renders
    (:func:`shipped_stack` over disjoint seed groups; ``kind`` ``renders``)."""
    options = dict(options or {})
    rows = []
    for name in transforms:
        if not reads_seed_mean(name):
            continue
        rows += measured_rows(
            renders, name, scene, settings,
            label=f"{scene.label}|renders|{name}",
            seed=derive_seed("calibration-renders", seed, scene.label, name),
            options=options.get(name),
            design={"replicate": 0, "kind": "renders", "strength": float("nan"),
                    "strength_factor": float("nan")},
            shipped_only=True,
        )
    return rows


def renders_output_rows(renders: dict, scene: SceneFrames, *, outputs: dict, settings,
                        seed: int = 0) -> list[dict]:
    """What a generator ships, measured on its own renders (``kind`` ``renders``), and the
    share of pixels whose variance its encoding fixes (method :data:`QUANTISED_SHARE`).

    Parameters
    ----------
    renders : dict
        View to the generator's renders (N, H, W, C), its own denoiser already applied.
    outputs : dict
        Label to the transform its renders pass through before they ship (its PNG writer,
        :mod:`stereovar.transforms.output`). The label is the chain its matched null passes
        through (``denoise+png8_filmic``: the null is drawn at the raw renders' level, so it
        also passes the denoiser the renderer ran), and the rows carry it, so that
        :func:`stereovar.statistics.mitigations.matched_difference` pairs them with that
        null.
    """
    from ..controls.quantisation import fixed_share, quantisation_variance
    from ..estimators.seeds import variance_field

    design = {"replicate": 0, "kind": "renders", "strength": float("nan"),
              "strength_factor": float("nan"), "null_kind": "camera"}
    rows = []
    for label, ship in outputs.items():
        encoding = output_encoding_of(ship)
        shipped = dataclasses.replace(scene, encoding=encoding) if encoding else scene
        stacks = {
            view: transform_stack(ship, renders[view], view=view,
                                  seed=derive_seed("calibration-output", seed, label, view))
            for view in ("left", "right")
        }
        for row in statistic_rows(stacks, shipped, settings, f"{scene.label}|output|{label}"):
            rows.append({**design, "transform": label, "region": row["region"],
                         "method": row["method"], "rho": row["rho"],
                         "boot_low": row["boot_low"], "boot_high": row["boot_high"],
                         "chance_se": row["chance_se"], "n_pixels": row["n_pixels"]})
        if encoding:
            shares = []
            for view, stack in stacks.items():
                mean, variance = variance_field(np.asarray(stack))
                q = quantisation_variance(mean, encoding)
                valid = np.asarray(scene.ground_truth[view]["valid"], dtype=bool)
                shares.append(fixed_share(variance[valid], q[valid]))
            rows.append({**design, "transform": label, "region": "all",
                         "method": QUANTISED_SHARE, "rho": max(shares),
                         "boot_low": float("nan"), "boot_high": float("nan"),
                         "chance_se": float("nan"), "n_pixels": int(valid.sum())})
    return rows


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


def camera_residual_variance(scene: SceneFrames, law, rng: np.random.Generator) -> float:
    """The estimation noise of :math:`\\ln\\sigma_L^2` at the scene's :math:`N`: the
    variance of the intensity control's residual on ``camera`` null frames (the
    :math:`\\operatorname{Var}(e_L^0)` of :func:`render_strength`), drawn with ``rng``."""
    from ..estimators.seeds import variance_field

    v = variance_fields(
        "camera", 0.0, mean=scene.mean, law=law, render_variance=scene.variance, rng=rng
    )
    _, null_field = variance_field(_encoded(
        draw_frames(scene.mean["left"], v["left"], scene.n_seeds, rng,
                    channel_correlation=scene.channel_correlation), scene.encoding))
    return _residual_variance(null_field, scene.mean["left"], scene)


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
        :data:`NONE` and the run's store transforms.
    settings : stereovar.statistics.fields.AnalysisSettings
        The run's analysis settings (bootstrap tile, replicates and seed).
    replicates : int
        Replicates of every design.
    strength_factors : sequence of float
        The planted strengths, as multiples of what the renders show (:func:`render_strength`);
        a transform sees those from :data:`TRANSFORM_MIN_FACTOR` up.
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
        :data:`CALIBRATED_METHODS` through the transforms).

    Returns
    -------
    rows : list of dict
        :data:`CALIBRATION_COLUMNS` (``scene`` left for the caller).
    info : dict
        ``camera_law`` (a, b), ``render_strength``, ``replicates`` and
        ``expensive_replicates``.
    """
    mu = {v: np.asarray(m, dtype=np.float64).mean(axis=-1) for v, m in scene.mean.items()}
    gt_valid = np.asarray(scene.ground_truth["left"]["valid"], dtype=bool)
    law = camera_law(scene.variance["left"], mu["left"], gt_valid)
    clean = scene.mean
    if scene.encoding:  # the law before the encoding, around the clean image behind it
        law, _ = encoded_clean(
            scene.mean["left"], scene.variance["left"], law, scene.n_seeds,
            np.random.default_rng(derive_seed("calibration-law", seed, scene.label)),
            scene.encoding)
        clean = {v: dequantised_mean(m, law, scene.encoding, scene.n_seeds)
                 for v, m in scene.mean.items()}
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
            frames = {view: _encoded(draw_frames(clean[view], v[view], scene.n_seeds, rng,
                                                 channel_correlation=scene.channel_correlation),
                                     scene.encoding)
                      for view in ("left", "right")}
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


def _encoded(frames, encoding):
    """``frames`` through the data's integer encoding, when it has one."""
    return frames if not encoding else integer_roundtrip(frames, **encoding)


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
