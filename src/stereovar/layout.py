"""Every result path of a run, keyed by (source, transform, estimator).

A run is **source → transform → estimator → analysis** (``DESIGN.md``). Its results sit
under one directory per source and transform, the *source key*:

``results/{source}``
    the source's own renders (``transform`` :data:`NONE`: the segment is left out, so the
    paths of runs without mitigations never changed);
``results/{source}/{transform}``
    the same scenes after a mitigation: a store transform (:mod:`stereovar.transforms`)
    applied to the source's renders, or a render-time policy (``shared_seed``) that renders
    them anew; or ``results/cycles/{profile}``, the scenes rendered by Cycles under a
    generator's own settings (:mod:`stereovar.generators`, the ``generators`` target).

``source`` is a renderer (``mitsuba``, ``cycles``) or an audit (``audit/{name}``). Under a
source key:

``renders/{scene}/{view}/spp{spp}/seeds{first}-{last}.zarr``
    one batch of renders of one view (:mod:`stereovar.io.renders`);
``renders/{scene}/{view}/spp{spp}/moments.zarr``
    one view's sample moments (:mod:`stereovar.io.moments`);
``renders/{scene}/{view}/aux.zarr``
    one view's auxiliary passes (albedo and normal) for the denoiser (source keys without a
    transform only);
``{estimator}/...``
    everything computed from those renders by one estimator: ``variance``, ``warped``,
    ``correlation``, ``intervention``, ``mitigation``, ``tables``, ``figures``;
``probe/{condition}/{arch}/{variant}/fold{f}/seed{j}.pt``, ``.../{arch}/tiles/fold{f}.csv``
    the learned probe's networks (of each training condition, architecture and variant: the
    network or its cue-blind twin) and their scores; ``probe/planted.json`` the planted
    control's strength and camera laws (under the run's source only).

Ground truth belongs to the scene, not to a transform: ``results/ground_truth/{scene}.zarr``
(traced for every renderer) or ``results/audit/{name}/ground_truth/{frame}.zarr`` (imported).
Tables across runs sit under ``results/tables/`` and figures across runs under
``results/figures/``; the page a person opens, the claims, the headline with its controls
and every figure, is ``results/index.html`` (:func:`results_page`).

The workflow's rules match the source key with one ``{renderer}`` wildcard
(:func:`source_key_pattern`), so every rule from the variance estimator to the tables runs
unchanged on transformed renders.

Importing this module pulls in no third-party package.
"""

from __future__ import annotations

import re

__all__ = [
    "AUDIT_PREFIX",
    "NONE",
    "RESULTS",
    "TABLE_FORMATS",
    "audit_source",
    "audit_summary",
    "audit_teaser",
    "audit_verdict",
    "aux_store",
    "claims_tables",
    "correlation_curve",
    "correlation_rows",
    "cross_renderer_figure",
    "cross_renderer_tables",
    "estimator_check_fields",
    "estimator_check_rows",
    "estimator_field_tables",
    "estimator_figure",
    "estimator_tables",
    "export_dir",
    "generator_calibration_rows",
    "generator_calibration_table",
    "generator_figure",
    "generator_source",
    "generator_tables",
    "ground_truth_store",
    "import_record",
    "intervention_margins",
    "intervention_metrics",
    "is_audit",
    "mitigation_figure",
    "mitigation_rows",
    "mitigation_tables",
    "moment_store",
    "preview",
    "probe_figure",
    "probe_model_tables",
    "probe_network",
    "probe_planted",
    "probe_tables",
    "probe_tiles",
    "probe_training_tables",
    "probe_verdict",
    "render_store",
    "results_page",
    "run_figure",
    "run_lock",
    "run_prefix",
    "run_tables",
    "scene_tables",
    "source_key",
    "source_key_pattern",
    "snakemake_report",
    "split_source_key",
    "summary_json",
    "table_paths",
    "traced_ground_truth",
    "variance_store",
    "warped_store",
]

RESULTS = "results"
"""The directory every result path starts with."""

NONE = "none"
"""The identity transform: the source's own renders, with no path segment."""

AUDIT_PREFIX = "audit/"
"""Source names of audits: ``audit/{name}``."""

TABLE_FORMATS = ("csv", "md", "tex", "html")
"""The formats every table is written in."""


def audit_source(name: str) -> str:
    """The source name of the audit ``name``: ``audit/{name}``."""
    return f"{AUDIT_PREFIX}{name}"


def is_audit(source: str) -> bool:
    """Whether a source (or source key) is an audit's (:func:`audit_source`)."""
    return str(source).startswith(AUDIT_PREFIX)


def source_key(source: str, transform: str = NONE) -> str:
    """The directory name of a source's renders after ``transform``, under ``results/``.

    Examples
    --------
    >>> source_key("mitsuba")
    'mitsuba'
    >>> source_key("mitsuba", "denoise")
    'mitsuba/denoise'
    >>> source_key("audit/team", "equalise")
    'audit/team/equalise'
    """
    transform = transform or NONE
    if "/" in transform or not transform:
        raise ValueError(f"a transform name has no '/', got {transform!r}")
    return str(source) if transform == NONE else f"{source}/{transform}"


def split_source_key(key: str) -> tuple[str, str]:
    """``(source, transform)`` of a source key (inverse of :func:`source_key`).

    Examples
    --------
    >>> split_source_key("mitsuba/denoise")
    ('mitsuba', 'denoise')
    >>> split_source_key("audit/team")
    ('audit/team', 'none')
    >>> split_source_key("audit/team/sensor_only")
    ('audit/team', 'sensor_only')
    """
    parts = str(key).split("/")
    n_source = 2 if is_audit(key) else 1
    if len(parts) not in (n_source, n_source + 1):
        raise ValueError(f"not a source key: {key!r}")
    source = "/".join(parts[:n_source])
    return source, parts[n_source] if len(parts) > n_source else NONE


def source_key_pattern(renderers, transforms) -> str:
    """The regular expression of a source key: a renderer or ``audit/{name}``, optionally
    followed by ``/{transform}`` (one of ``transforms``, never :data:`NONE`)."""
    source = "|".join(
        [*(re.escape(r) for r in renderers), re.escape(AUDIT_PREFIX) + r"[A-Za-z0-9_-]+"]
    )
    names = [re.escape(t) for t in transforms if t != NONE]
    suffix = f"(?:/(?:{'|'.join(names)}))?" if names else ""
    return f"(?:{source}){suffix}"


def render_store(source: str, scene: str, view: str, spp, batch, transform: str = NONE) -> str:
    """One batch of renders:
    ``results/{source}[/{transform}]/renders/{scene}/{view}/spp{spp}/seeds{batch}.zarr``."""
    key = source_key(source, transform)
    return f"{RESULTS}/{key}/renders/{scene}/{view}/spp{spp}/seeds{batch}.zarr"


def moment_store(source: str, scene: str, view: str, spp, transform: str = NONE) -> str:
    """One view's moment store:
    ``results/{source}[/{transform}]/renders/{scene}/{view}/spp{spp}/moments.zarr``."""
    key = source_key(source, transform)
    return f"{RESULTS}/{key}/renders/{scene}/{view}/spp{spp}/moments.zarr"


def aux_store(source: str, scene: str, view: str) -> str:
    """One view's auxiliary passes (albedo, normal) for the denoiser:
    ``results/{source}/renders/{scene}/{view}/aux.zarr``."""
    return f"{RESULTS}/{source}/renders/{scene}/{view}/aux.zarr"


def ground_truth_store(source: str, scene: str) -> str:
    """A scene's ground truth: ``results/ground_truth/{scene}.zarr``, traced from the scene
    for every renderer and transform, or ``results/audit/{name}/ground_truth/{frame}.zarr``,
    imported with an audit's renders. ``source`` may be a source key."""
    source, _ = split_source_key(source)
    if is_audit(source):
        return f"{RESULTS}/{source}/ground_truth/{scene}.zarr"
    return traced_ground_truth(scene)


def traced_ground_truth(scene: str) -> str:
    """A scene's ground truth traced from its spec: ``results/ground_truth/{scene}.zarr``."""
    return f"{RESULTS}/ground_truth/{scene}.zarr"


def run_prefix(source: str, estimator: str, transform: str = NONE) -> str:
    """Directory of everything computed from one source's renders after ``transform`` by
    one estimator: ``results/{source}[/{transform}]/{estimator}``."""
    return f"{RESULTS}/{source_key(source, transform)}/{estimator}"


def variance_store(source: str, estimator: str, scene: str, spp, transform: str = NONE) -> str:
    """Both views' variance (Eq. 1):
    ``results/{source}[/{transform}]/{estimator}/variance/{scene}/spp{spp}.zarr``."""
    return f"{run_prefix(source, estimator, transform)}/variance/{scene}/spp{spp}.zarr"


def warped_store(source: str, estimator: str, scene: str, spp, transform: str = NONE) -> str:
    """The right view's variance warped to the left (Eq. 2):
    ``results/{source}[/{transform}]/{estimator}/warped/{scene}/spp{spp}.zarr``."""
    return f"{run_prefix(source, estimator, transform)}/warped/{scene}/spp{spp}.zarr"


def correlation_rows(source: str, estimator: str, scene: str, spp, transform: str = NONE) -> str:
    """One scene's statistics and controls (Eq. 3):
    ``results/{source}[/{transform}]/{estimator}/correlation/{scene}/spp{spp}.csv``."""
    return f"{run_prefix(source, estimator, transform)}/correlation/{scene}/spp{spp}.csv"


def correlation_curve(source: str, estimator: str, scene: str, spp, transform: str = NONE) -> str:
    """One scene's rho against the number of seeds:
    ``results/{source}[/{transform}]/{estimator}/correlation/{scene}/spp{spp}_curve.csv``."""
    return f"{run_prefix(source, estimator, transform)}/correlation/{scene}/spp{spp}_curve.csv"


def intervention_metrics(source: str, estimator: str, scene: str, transform: str = NONE) -> str:
    """One scene's intervention metrics (Sec. 3.4):
    ``results/{source}[/{transform}]/{estimator}/intervention/{scene}.csv``."""
    return f"{run_prefix(source, estimator, transform)}/intervention/{scene}.csv"


def intervention_margins(source: str, estimator: str, scene: str, transform: str = NONE) -> str:
    """One scene's sampled ground-truth margins of the intervention:
    ``results/{source}[/{transform}]/{estimator}/intervention/margins/{scene}.csv``."""
    return f"{run_prefix(source, estimator, transform)}/intervention/margins/{scene}.csv"


def run_tables(source: str, estimator: str, name: str, transform: str = NONE) -> list[str]:
    """A table of one run in every format:
    ``results/{source}[/{transform}]/{estimator}/tables/{name}.*``."""
    return table_paths(name, f"{run_prefix(source, estimator, transform)}/tables")


def run_figure(source: str, estimator: str, name: str, transform: str = NONE) -> str:
    """A figure of one run: ``results/{source}[/{transform}]/{estimator}/figures/{name}.png``."""
    return f"{run_prefix(source, estimator, transform)}/figures/{name}.png"


def preview(source: str, scene: str) -> str:
    """A scene's preview by one renderer: ``results/{source}/previews/{scene}.png``."""
    return f"{RESULTS}/{source}/previews/{scene}.png"


def estimator_check_fields(source: str, scene: str, spp) -> str:
    """One scene's moment field against the seeds' (``estimators``):
    ``results/{source}/estimators/{scene}/spp{spp}_fields.csv``."""
    return f"{RESULTS}/{source}/estimators/{scene}/spp{spp}_fields.csv"


def estimator_check_rows(source: str, scene: str, spp) -> str:
    """One scene's statistics by both estimators (``estimators``):
    ``results/{source}/estimators/{scene}/spp{spp}.csv``."""
    return f"{RESULTS}/{source}/estimators/{scene}/spp{spp}.csv"


def export_dir(source: str, estimator: str, fmt: str, scene: str) -> str:
    """One scene exported as files other tools read:
    ``results/export/{source}/{estimator}/{fmt}/{scene}``."""
    return f"{RESULTS}/export/{source}/{estimator}/{fmt}/{scene}"


def import_record(name: str, frame: str) -> str:
    """The import record of one frame of an audit: ``results/audit/{name}/import/{frame}.json``."""
    return f"{RESULTS}/{audit_source(name)}/import/{frame}.json"


def audit_seeding(name: str, frame: str) -> str:
    """One frame's cross-view residual correlations of an audit (do the views share their
    random streams?): ``results/audit/{name}/seeding/{frame}.csv``."""
    return f"{RESULTS}/{audit_source(name)}/seeding/{frame}.csv"


def audit_thumbnail(name: str, frame: str) -> str:
    """One frame's thumbnail (a render and the disparity, to see that the right files were
    read): ``results/audit/{name}/figures/thumbnail_{frame}.png``."""
    return f"{RESULTS}/{audit_source(name)}/figures/thumbnail_{frame}.png"


def audit_strongest(name: str) -> str:
    """The verdict page's figure of where the cue is strongest (the top frames with their top
    tiles): ``results/audit/{name}/figures/strongest.png``."""
    return f"{RESULTS}/{audit_source(name)}/figures/strongest.png"


def audit_teaser(name: str, scene: str) -> str:
    """One frame's teaser of an audit: ``results/audit/{name}/figures/teaser_{scene}.png``."""
    return f"{RESULTS}/{audit_source(name)}/figures/teaser_{scene}.png"


def audit_verdict(name: str, ext: str) -> str:
    """An audit's verdict page (``md`` or ``html``): ``results/audit/{name}/verdict.{ext}``."""
    return f"{RESULTS}/{audit_source(name)}/verdict.{ext}"


def audit_summary(name: str) -> str:
    """An audit's verdict as numbers: ``results/audit/{name}/summary.json``."""
    return f"{RESULTS}/{audit_source(name)}/summary.json"


def mitigation_rows(source: str, estimator: str, scene: str, spp, transform: str = NONE) -> str:
    """One scene's mitigation measurements (residual correlations and image quality):
    ``results/{source}[/{transform}]/{estimator}/mitigation/{scene}/spp{spp}.csv``."""
    return f"{run_prefix(source, estimator, transform)}/mitigation/{scene}/spp{spp}.csv"


def calibration_rows(source: str, estimator: str, scene: str, spp) -> str:
    """One scene's calibration replicates (synthetic nulls and planted cues through every
    transform and statistic), drawn as the estimator's variance store was:
    ``results/{source}/{estimator}/calibration/{scene}/spp{spp}.csv``."""
    return f"{run_prefix(source, estimator)}/calibration/{scene}/spp{spp}.csv"


def dose_response_rows(source: str, scene: str, spp) -> str:
    """One scene's dose-response rows (what a seed-mean mitigation ships over its budget and
    the camera, predicted and measured): ``results/{source}/seeds/dose_response/{scene}/
    spp{spp}.csv``."""
    return f"{run_prefix(source, 'seeds')}/dose_response/{scene}/spp{spp}.csv"


def dose_response_tables(source: str | None = None) -> list[str]:
    """The dose-response table: ``results/tables/dose_response.{csv,md,tex,html}``, or an
    audit's under ``results/audit/{name}/tables``."""
    if source is not None and is_audit(source):
        return table_paths("dose_response", f"{RESULTS}/{source}/tables")
    return table_paths("dose_response")


def generator_source(profile: str) -> str:
    """The source key of a generator profile's renders (:mod:`stereovar.generators`):
    ``cycles`` for the paper's own settings, else ``cycles/{profile}``."""
    from .generators import PAPER

    return "cycles" if profile == PAPER else source_key("cycles", profile)


def generator_calibration_rows(profile: str, scene: str, spp) -> str:
    """One scene's calibration replicates matched to a generator profile (its camera-law
    nulls, through its denoiser where it has one):
    ``results/cycles/seeds/generator_calibration/{profile}/{scene}/spp{spp}.csv``."""
    return f"{run_prefix('cycles', 'seeds')}/generator_calibration/{profile}/{scene}/spp{spp}.csv"


def generator_tables() -> list[str]:
    """The generator table: ``results/tables/generators.{csv,md,tex,html}`` (every column,
    and each number beside its interval and matched null)."""
    return table_paths("generators")


def generator_calibration_table() -> str:
    """The calibration of the generator table's verdicts, every profile against its own
    matched nulls (every check, scope and design): ``results/tables/generators_calibration.csv``."""
    return f"{RESULTS}/tables/generators_calibration.csv"


def generator_figure() -> str:
    """The generator figure: ``results/figures/generators.png``."""
    return f"{RESULTS}/figures/generators.png"


def calibration_tables(source: str | None = None) -> list[str]:
    """The calibration table (``csv``, ``md``): ``results/tables/calibration.*``, or
    ``results/audit/{name}/tables/calibration.*`` for an audit."""
    prefix = f"{RESULTS}/{source}/tables" if source and is_audit(source) else f"{RESULTS}/tables"
    return [f"{prefix}/calibration.{ext}" for ext in ("csv", "md")]


def calibration_nulls(source: str | None = None) -> str:
    """Each scene's matched null per transform and statistic, and the equivalence margins:
    ``results/tables/calibration_nulls.csv`` (an audit's under ``results/audit/{name}``)."""
    prefix = f"{RESULTS}/{source}/tables" if source and is_audit(source) else f"{RESULTS}/tables"
    return f"{prefix}/calibration_nulls.csv"


def calibration_figure(source: str | None = None) -> str:
    """The calibration figure: ``results/figures/calibration.png`` (an audit's under
    ``results/audit/{name}``)."""
    if source is not None and is_audit(source):
        return f"{RESULTS}/{source}/figures/calibration.png"
    return f"{RESULTS}/figures/calibration.png"


def table_paths(name: str, prefix: str = f"{RESULTS}/tables") -> list[str]:
    """A table in every :data:`TABLE_FORMATS`: ``{prefix}/{name}.{ext}``."""
    return [f"{prefix}/{name}.{ext}" for ext in TABLE_FORMATS]


def mitigation_figure(source: str | None = None) -> str:
    """The mitigation trade-off figure: ``results/figures/mitigations.png``, or
    ``results/audit/{name}/figures/mitigations.png`` for an audit."""
    if source is not None and is_audit(source):
        return f"{RESULTS}/{source}/figures/mitigations.png"
    return f"{RESULTS}/figures/mitigations.png"


def mitigation_tables(source: str | None = None) -> list[str]:
    """The mitigation table: ``results/tables/mitigations.*`` for the run's renderer, or
    ``results/audit/{name}/tables/mitigations.*`` for an audit."""
    if source is not None and is_audit(source):
        return table_paths("mitigations", f"{RESULTS}/{source}/tables")
    return table_paths("mitigations")


def mitigation_headline_tables(source: str | None = None) -> list[str]:
    """The mitigation table's headline (at most 8 columns, what the pages show):
    ``results/tables/mitigations_headline.*``, or an audit's under
    ``results/audit/{name}/tables``."""
    if source is not None and is_audit(source):
        return table_paths("mitigations_headline", f"{RESULTS}/{source}/tables")
    return table_paths("mitigations_headline")


def probe_network(source: str, condition: str, arch: str, variant: str, fold, seed) -> str:
    """One trained probe network: architecture ``arch``, training ``condition``, ``variant``
    (``main`` or its cue-blind ``twin``), fold and training seed:
    ``results/{source}/probe/{condition}/{arch}/{variant}/fold{fold}/seed{seed}.pt``."""
    return f"{RESULTS}/{source}/probe/{condition}/{arch}/{variant}/fold{fold}/seed{seed}.pt"


def probe_tiles(source: str, condition: str, arch: str, fold) -> str:
    """The per-tile scores of every network of ``arch`` tested on one fold's held-out scenes
    under ``condition`` (its network, its twin and the control's):
    ``results/{source}/probe/{condition}/{arch}/tiles/fold{fold}.csv``."""
    return f"{RESULTS}/{source}/probe/{condition}/{arch}/tiles/fold{fold}.csv"


def probe_planted(source: str) -> str:
    """The planted positive control's settings measured on the renders (their strength and each
    scene's camera law): ``results/{source}/probe/planted.json``."""
    return f"{RESULTS}/{source}/probe/planted.json"


def probe_tables(source: str | None = None) -> list[str]:
    """The probe table: ``results/tables/probe.*``, or ``results/audit/{name}/tables/probe.*``
    for an audit."""
    if source is not None and is_audit(source):
        return table_paths("probe", f"{RESULTS}/{source}/tables")
    return table_paths("probe")


def probe_training_tables(source: str | None = None) -> list[str]:
    """The probe's training table (steps to the plateau, validation accuracy):
    ``results/tables/probe_training.*``, or an audit's under ``results/audit/{name}/tables``."""
    if source is not None and is_audit(source):
        return table_paths("probe_training", f"{RESULTS}/{source}/tables")
    return table_paths("probe_training")


def probe_model_tables(source: str | None = None) -> list[str]:
    """The user's own network on the counterfactual inputs (``stereovar probe``,
    ``audit.probe_model``): ``results/tables/probe_model.*``, or
    ``results/audit/{name}/tables/probe_model.*`` for an audit."""
    if source is not None and is_audit(source):
        return table_paths("probe_model", f"{RESULTS}/{source}/tables")
    return table_paths("probe_model")


def probe_figure(source: str | None = None) -> str:
    """Accuracy per test input for each training condition: ``results/figures/probe.png``,
    or ``results/audit/{name}/figures/probe.png`` for an audit."""
    if source is not None and is_audit(source):
        return f"{RESULTS}/{source}/figures/probe.png"
    return f"{RESULTS}/figures/probe.png"


def probe_verdict(source: str | None = None) -> str:
    """The probe's verdict as numbers: ``results/tables/probe_verdict.json``, or
    ``results/audit/{name}/tables/probe_verdict.json`` for an audit."""
    if source is not None and is_audit(source):
        return f"{RESULTS}/{source}/tables/probe_verdict.json"
    return f"{RESULTS}/tables/probe_verdict.json"


def scene_tables() -> list[str]:
    """The scene summary: ``results/tables/scenes.*``."""
    return table_paths("scenes")


def claims_tables() -> list[str]:
    """The claims table: ``results/tables/claims.*``."""
    return table_paths("claims")


def summary_json() -> str:
    """The run's headline numbers: ``results/summary.json``."""
    return f"{RESULTS}/summary.json"


def results_page() -> str:
    """The run's results page, the one page a person opens: ``results/index.html``."""
    return f"{RESULTS}/index.html"


def run_lock(scope: str) -> str:
    """The lock file a ``stereovar`` command holds while it may write ``scope``'s results
    (:mod:`stereovar.run_lock`): ``results/.locks/{scope}.lock``, where ``scope`` is ``run``
    (the workflow's own results) or ``audit-{name}`` (``results/audit/{name}/``).

    Examples
    --------
    >>> run_lock("audit-my_renders")
    'results/.locks/audit-my_renders.lock'
    """
    return f"{RESULTS}/.locks/{scope}.lock"


def snakemake_report() -> str:
    """Snakemake's report of the run (``snakemake --report``), which the results page links
    when it exists: ``results/report.html``."""
    return f"{RESULTS}/report.html"


def cross_renderer_tables() -> list[str]:
    """The renderers side by side: ``results/tables/cross_renderer.*``."""
    return table_paths("cross_renderer")


def cross_renderer_figure() -> str:
    """The renderers' variance fields: ``results/figures/cross_renderer.png``."""
    return f"{RESULTS}/figures/cross_renderer.png"


def estimator_tables() -> list[str]:
    """Seeds against moments, every statistic: ``results/tables/estimators.*``."""
    return table_paths("estimators")


def estimator_field_tables() -> list[str]:
    """Seeds against moments, the fields: ``results/tables/estimator_fields.*``."""
    return table_paths("estimator_fields")


def estimator_figure() -> str:
    """Seeds against moments: ``results/figures/estimators.png``."""
    return f"{RESULTS}/figures/estimators.png"
