# Configuration validation, wildcard constraints, the run's settings and the input functions
# several features share; each feature's own are in inputs/<feature>.smk (included at the end).
import json
import re
import sys
from pathlib import Path
from types import SimpleNamespace

from snakemake.utils import validate

from stereovar.config import validate_config_or_exit
from stereovar.errors import exit_with_one_line
from stereovar.io.contracts import config_digest
from stereovar.preflight import (
    STATE_DIR,
    WRITTEN_FOLDERS,
    check_backends,
    check_scene_specs,
    check_writable,
    clear_stale_lock,
    mark_run,
    stored_backends,
)
from stereovar.io.store import set_rerun_arguments
from stereovar.scenes.references import xml_references
from stereovar.estimators import ESTIMATORS
from stereovar.audit.run import (
    audit_paths,
    audit_run_config,
    audit_targets,
    discover_audit,
    frame_files,
    frame_pattern,
    import_fingerprint,
    import_outputs,
    import_params,
    check_audit_memory,
    set_aside_verdict,
)
from stereovar.experiment import (
    AUDIT_PREFIX,
    batch_seeds,
    estimator_stores,
    ground_truth_store,
    intervention_renders,
    render_stores as configured_stores,
    scene_spp_pairs,
    seed_stores,
)
from stereovar.renderers import RENDERERS
from stereovar import layout
from stereovar.mitigations import (
    MITIGATION_ESTIMATOR,
    SEED_POLICY_MITIGATIONS,
    audit_mitigation_runs,
    keyed_transforms,
    mitigation_runs,
)
from stereovar.transforms import TRANSFORMS
from stereovar.rig import VIEWS
from stereovar import resources as sizing
from stereovar.workflow_inputs import resources as job_requests

CONFIG_SCHEMA = "../schemas/config.schema.yaml"

config.update(
    validate_config_or_exit(
        config,
        workflow.source_path(CONFIG_SCHEMA),
        command_line=workflow.config_settings.config,
    )
)


validate(config, CONFIG_SCHEMA, set_default=True)

# Every directory the run writes (stereovar.preflight.WRITTEN_FOLDERS, Snakemake's own
# .snakemake included) must be writable, checked before anything (an audit's import
# included) is written; Snakemake would stop with a ProtectedOutputException, or a
# job would fail, naming no fix. A report only reads the results.
if workflow.is_main_process and not any(a.startswith("--report") for a in sys.argv):
    with exit_with_one_line():
        check_writable(WRITTEN_FOLDERS)

# An `audit:` section turns the run into an audit of renders made elsewhere: its files are
# found here (templates globbed; nothing is read, hashed or written) and imported into the
# render and ground-truth store contracts by one `audit_import` job per frame (audit.smk);
# the run's scenes, renderer ("audit/<name>"), N and SPP become the audit's
# (stereovar.audit.run).
AUDIT = config.get("audit")
if AUDIT:
    with exit_with_one_line():
        AUDIT_DISCOVERY = discover_audit(AUDIT)
    config.update(audit_run_config(config, AUDIT_DISCOVERY))

# A job that asks for more memory than the machine, the cluster (cluster.max_mem_mb) or
# --resources mem_mb allows could never run: stop before any job (stereovar.resources).
if workflow.is_main_process:
    _global_mem = workflow.global_resources.get("mem_mb")
    _limit = sizing.memory_limit(
        config, global_mem_mb=None if _global_mem is None else _global_mem.value
    )
    with exit_with_one_line():
        if AUDIT:  # the size is the renders', not a config key
            check_audit_memory(config, AUDIT_DISCOVERY, *_limit)
        else:
            sizing.check_job_memory(config, *_limit)


ENV = "../../envs/stereovar.yaml"
SCENES = list(config["scenes"])


# {renderer} is a source key (stereovar.layout): a renderer or an audit, optionally followed
# by a mitigation's transform ("mitsuba/denoise"), so every rule from the variance estimator
# to the tables runs unchanged on transformed renders. Rules that render constrain it to
# RENDERER_NAMES; the transform rule to SOURCE_NAMES.
wildcard_constraints:
    scene=r"[A-Za-z0-9_-]+",
    view="|".join(VIEWS),
    spp=r"\d+",
    batch=r"\d+-\d+",
    renderer=layout.source_key_pattern(RENDERERS, keyed_transforms()),
    estimator="|".join(ESTIMATORS),
    transform="|".join(TRANSFORMS),
    policy="|".join(SEED_POLICY_MITIGATIONS),
    fold=r"\d+",
    train_seed=r"\d+",


WIDTH = config["resolution"]["width"]
HEIGHT = config["resolution"]["height"]
CLUSTER = config["cluster"]
# Render jobs run one thread each locally, so two jobs share a 2-core machine: two 1-thread
# jobs at once render 1.09x the samples per second of one 2-thread job at a time, and two
# 2-thread jobs at once 1.01x (bench/render_throughput.py --options). A job that renders
# alone gets more with `--set-threads render=2`. Cluster jobs get cluster.render_threads.
RENDER_THREADS = 1 if workflow.local_exec else CLUSTER["render_threads"]
N_SEEDS = config["render"]["n_seeds"]
INTERVENTION_N_SEEDS, INTERVENTION_SPP = intervention_renders(config)
# renders read per view by the variance job: what the estimator declares it reads
ESTIMATOR_READS = ESTIMATORS.get(config["render"]["estimator"]).renders_per_view(N_SEEDS)
MAIN_SPP = config["render"]["spp"]
VALIDATION_N_SEEDS = config["validation"]["n_seeds"]
VALIDATION_SPP = config["validation"]["spp"] or MAIN_SPP
SWEEP_SCENE = config["render"]["spp_sweep"]["scene"]
SWEEP_SPP = sorted(config["render"]["spp_sweep"]["spp"])
INTERVENTION_ESTIMATOR = "seeds"  # the intervention splits seeds into mean and residuals


def get_renderer():
    """The renderer of this run (``render.renderer``)."""
    return config["render"]["renderer"]


def get_estimator():
    """The variance estimator of this run (``render.estimator``)."""
    return config["render"]["estimator"]



# `renderers: [mitsuba, cycles]` runs the experiment for each renderer (render.renderer is
# the primary one: the claims table and summary.json); the cross-renderer table and figure
# compare them.
RENDERER_RUNS = list(dict.fromkeys(config.get("renderers") or [get_renderer()]))


def renderer_config(renderer):
    """This config with ``render.renderer`` set to ``renderer``."""
    return {**config, "render": {**config["render"], "renderer": renderer}}


def cross_renderer_inputs(path, scenes):
    """``path(source, estimator, scene, spp)`` (a :mod:`stereovar.layout` function) of
    ``scenes`` at the main SPP per renderer run, as named input lists."""
    return {r: [path(r, get_estimator(), s, MAIN_SPP) for s in scenes] for r in RENDERER_RUNS}


def wildcard_renderer(wildcards):
    """A job's renderer: its ``{renderer}`` wildcard, else ``render.renderer``."""
    return getattr(wildcards, "renderer", None) or get_renderer()


# The wildcard constraint of rules that render: a renderer, never an audit's imported source.
RENDERER_NAMES = "|".join(RENDERERS)
# The wildcard constraint of the transform rule's source: a renderer or an audit, untransformed.
SOURCE_NAMES = layout.source_key_pattern(RENDERERS, ())


def ground_truth_input(wildcards):
    """The ground truth of the wildcards' scene: traced or, for an audit, imported
    (:func:`stereovar.layout.ground_truth_store`)."""
    return ground_truth_store(wildcards.renderer, wildcards.scene)


# Result paths (stereovar.layout): renders under results/{renderer}/renders/, everything
# computed from them under results/{renderer}/{estimator}/; the intervention always uses the
# seeds estimator, so its results sit under results/{renderer}/seeds/.


def run_config(renderer):
    """This config with ``renderer`` as ``render.renderer`` (for the path helpers)."""
    return {**config, "render": {**config["render"], "renderer": renderer}}


def scene_files(path, estimator=None):
    """Input function: ``path(source, estimator, scene, spp)`` (a :mod:`stereovar.layout`
    function) for every scene at the main SPP, in the wildcards' run (or the wildcards'
    renderer and ``estimator``)."""

    def inputs(wildcards):
        run = (wildcards.renderer, estimator or wildcards.estimator)
        return [path(*run, s, MAIN_SPP) for s in SCENES]

    return inputs


def scene_results(path, estimator=None):
    """Input function: ``path(source, estimator, scene)`` (a :mod:`stereovar.layout` function
    without an SPP: the intervention's) for every scene, in the wildcards' run (or the
    wildcards' renderer and ``estimator``)."""

    def inputs(wildcards):
        return [path(wildcards.renderer, estimator or wildcards.estimator, s) for s in SCENES]

    return inputs


def sweep_inputs(path):
    """Input function: ``path(source, estimator, scene, spp)`` for the sweep scene at each
    sweep SPP, ascending, in the wildcards' run."""

    def inputs(wildcards):
        run = (wildcards.renderer, wildcards.estimator)
        return [path(*run, SWEEP_SCENE, spp) for spp in SWEEP_SPP]

    return inputs


def main_scene_file(path, scene=None):
    """Input function: ``path(source, estimator, scene, spp)`` for the sweep scene (or
    ``scene``) at the main SPP, in the wildcards' run."""

    def inputs(wildcards):
        return path(wildcards.renderer, wildcards.estimator, scene or SWEEP_SCENE, MAIN_SPP)

    return inputs


def table_outputs(paths, prefix="", **report_args):
    """Named outputs of one table in every format (:func:`stereovar.layout.table_paths`):
    ``{prefix}csv``, ``{prefix}md``, ``{prefix}tex`` and ``{prefix}html``, the last in the
    report with ``report_args`` (caption, category, labels)."""
    named = {f"{prefix}{ext}": p for ext, p in zip(layout.TABLE_FORMATS, paths, strict=True)}
    named[f"{prefix}html"] = report(named[f"{prefix}html"], **report_args)
    return named


def analysis_resources(images, n_reads):
    """Memory and runtime requests of an analysis job holding ``images`` images at once and
    reading ``n_reads`` renders (:func:`stereovar.workflow_inputs.resources.analysis_resources`)."""
    return job_requests.analysis_resources(WIDTH, HEIGHT, images, n_reads)


# Each feature's input functions, params, cluster requests and targets, beside its rule file
# (workflow/rules/<feature>.smk). Read in this order: a config error stops the run at the
# first file that finds one.
include: "inputs/audit.smk"
include: "inputs/scenes.smk"
include: "inputs/render.smk"
include: "inputs/targets.smk"
include: "inputs/estimators.smk"
include: "inputs/intervention.smk"
include: "inputs/run.smk"
include: "inputs/mitigations.smk"
include: "inputs/calibration.smk"
include: "inputs/probe.smk"
include: "inputs/pages.smk"
include: "inputs/generators.smk"
