# Configuration validation, wildcard constraints, input functions and target lists.
import json
import math
import re
import shlex
import sys
from pathlib import Path
from types import SimpleNamespace

import yaml
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
from stereovar.io.renders import set_rerun_arguments
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
from stereovar.transforms import TRANSFORMS, get_transform
from stereovar.rig import VIEWS
from stereovar import resources as sizing

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
GENERATED_SCENE = r"scene_\d{3}"


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


def estimator_inputs(wildcards):
    """The stores the estimator reads for one scene at one SPP: all N seeds' render
    stores (``seeds``) or the moment store (``moments``) of each view."""
    return estimator_stores(
        run_config(wildcards.renderer), wildcards.scene, wildcards.spp, wildcards.estimator
    )


def intervention_inputs(wildcards):
    """The intervention's seeds (``intervention.n_seeds`` at ``intervention.spp``) of both
    views of one scene, and its ground truth."""
    return {
        **seed_stores(
            run_config(wildcards.renderer),
            wildcards.scene,
            INTERVENTION_SPP,
            INTERVENTION_N_SEEDS,
        ),
        "ground_truth": ground_truth_input(wildcards),
    }


def audit_frame_inputs(wildcards):
    """One imported frame's render stores (every seed of each view) and ground truth."""
    source = layout.audit_source(wildcards.name)
    return {
        **seed_stores(run_config(source), wildcards.scene, MAIN_SPP),
        "ground_truth": layout.ground_truth_store(source, wildcards.scene),
    }


def estimator_check_inputs(wildcards):
    """One scene's moment stores, its ``validation.n_seeds`` seed renders at the same SPP
    and its ground truth (``estimator_check``)."""
    run = run_config(wildcards.renderer)
    moments = estimator_stores(run, wildcards.scene, wildcards.spp, "moments")
    seeds = seed_stores(run, wildcards.scene, wildcards.spp, VALIDATION_N_SEEDS)
    return {
        **{f"moments_{view}": paths[0] for view, paths in moments.items()},
        **{f"seeds_{view}": paths for view, paths in seeds.items()},
        "ground_truth": ground_truth_input(wildcards),
    }


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


AUDIT_FOUND = AUDIT_DISCOVERY.summary() if AUDIT else ""
EXPORT_FORMATS = config["export"]["formats"]


def export_inputs(wildcards):
    """One scene's render stores at the main SPP, its variance store and its ground truth,
    for ``export_scene``."""
    run = run_config(wildcards.renderer)
    stores = estimator_stores(run, wildcards.scene, MAIN_SPP, "seeds")
    variance = layout.variance_store(
        wildcards.renderer, wildcards.estimator, wildcards.scene, MAIN_SPP
    )
    return {
        **stores,
        "variance": variance,
        "ground_truth": ground_truth_input(wildcards),
    }


def export_targets():
    """``snakemake export``: every scene of this run in every ``export.formats`` format."""
    run = (get_renderer(), get_estimator())
    return [layout.export_dir(*run, fmt, s) for fmt in EXPORT_FORMATS for s in SCENES]


def scene_spec_path(scene):
    """Path of a scene's spec file."""
    return f"scenes/{scene}.yaml"


def scene_inputs(wildcards):
    """The spec of a scene and, for XML scenes, the Mitsuba file it points at and every
    file that reads (meshes, textures, includes), so editing any of them reruns the scene."""
    spec = Path(scene_spec_path(wildcards.scene))
    inputs = {"spec": str(spec)}
    if spec.is_file():
        data = yaml.safe_load(spec.read_text()) or {}
        if isinstance(data, dict) and isinstance(data.get("mitsuba_xml"), str):
            xml = spec.parent / data["mitsuba_xml"]
            inputs["xml"] = str(xml)
            inputs["xml_files"] = [str(p) for p in xml_references(xml)]
    return inputs


def rig_params():
    """Renderer, resolution and rig settings shared by every job that builds the stereo rig."""
    return {
        "renderer": wildcard_renderer,
        "width": config["resolution"]["width"],
        "height": config["resolution"]["height"],
        "baseline_m": config["rig"]["baseline_m"],
        "convention": config["rig"]["convention"],
        "variant": config["render"]["variant"],
    }


def render_params():
    """Integrator, filter, sampler and seed-policy settings of every render."""
    r = config["render"]
    return {
        "variant": r["variant"],
        "integrator": r["integrator"],
        "max_depth": r["max_depth"],
        "rfilter": r["rfilter"],
        "sampler": r["sampler"],
        "seed_policy": r["seed_policy"],
        **renderer_options(),
    }


def renderer_options():
    """The options only a job's renderer reads (``render.cycles`` for Cycles, with every
    default filled in, so each render records them); a param function of the wildcards."""

    def options(wildcards):
        if wildcard_renderer(wildcards) != "cycles":
            return {}
        from stereovar.renderers.cycles.settings import cycles_options

        return cycles_options(config["render"].get("cycles"))

    # a run without Cycles keeps the params (and so the DAG) it always had
    return {"renderer_options": options} if "cycles" in RENDERER_RUNS else {}


def missing_scene_specs():
    """Listed scenes without a spec file: ``(generatable, unknown)``.

    Only ``scene_NNN`` specs can be generated; an existing spec is never regenerated by the
    workflow (committed or edited specs stay as they are).
    """
    if AUDIT:  # an audit's frames are files, not scene specs
        return [], []
    missing = [s for s in SCENES if not Path(scene_spec_path(s)).is_file()]
    generatable = [s for s in missing if re.fullmatch(GENERATED_SCENE, s)]
    return generatable, [s for s in missing if s not in generatable]


TO_GENERATE, UNKNOWN_SCENES = missing_scene_specs()
if UNKNOWN_SCENES:
    raise SystemExit(
        f"stereovar: config key 'scenes': no spec file for {', '.join(UNKNOWN_SCENES)} "
        "(expected scenes/<name>.yaml); add the spec or remove the name from 'scenes'"
    )
# Every existing spec, with the XML file it points at and the files that reads, is checked
# here, before any job starts: a job that found the problem would first have its outputs
# deleted by Snakemake.
with exit_with_one_line():
    check_scene_specs(
        scene_spec_path(s) for s in SCENES if s not in TO_GENERATE and not AUDIT
    )
# The generator rule only applies to specs that are missing (a pattern matching nothing
# otherwise), so it never overwrites a committed or edited spec.
GENERATE_PATTERN = "|".join(re.escape(s) for s in TO_GENERATE) or r"(?!x)x"


def all_targets():
    """Everything `snakemake all` builds, for the configured renderer and estimator (for an
    audit: its verdict page and everything behind it, :func:`stereovar.audit.run.audit_targets`)."""
    if AUDIT:
        return [
            *render_stores(),
            *audit_targets(config),
            *mitigation_targets(),
            *calibration_targets(),
            *probe_targets(),
            *(layout.probe_model_tables(get_renderer()) if AUDIT.get("probe_model") else []),
        ]
    shared = [
        *[layout.traced_ground_truth(s) for s in SCENES],
        *layout.scene_tables(),
        *layout.claims_tables(),
        layout.summary_json(),
        *mitigation_targets(),
        *calibration_targets(),
        *probe_if_run(),
        layout.results_page(),
    ]
    if len(RENDERER_RUNS) > 1:
        shared += [
            *layout.cross_renderer_tables(),
            layout.cross_renderer_figure(),
        ]
    per_renderer = [p for r in RENDERER_RUNS for p in renderer_targets(r)]
    return list(dict.fromkeys([*per_renderer, *shared]))


def renderer_targets(renderer):
    """Everything `snakemake all` builds for one renderer."""
    run = (renderer, get_estimator())
    intervention = (renderer, INTERVENTION_ESTIMATOR)
    return [
        # The renders are targets too, so a render store lost after its analysis finished is
        # rebuilt (from the render cache) instead of silently missing.
        *render_stores(renderer),
        *[layout.preview(renderer, s) for s in SCENES],
        *[layout.correlation_rows(*run, s, spp) for s, spp in scene_spp_pairs(config)],
        *[
            p
            for name in ["cross_scene", "spp_sweep", "spp_sweep_fit"]
            for p in layout.run_tables(*run, name)
        ],
        *[layout.intervention_metrics(*intervention, s) for s in SCENES],
        *layout.run_tables(*intervention, "intervention"),
        layout.run_figure(*run, "fig1_teaser"),
        layout.run_figure(*run, "fig2_rho_vs_spp"),
        layout.run_figure(*run, "fig3_material_scatter"),
        layout.run_figure(*intervention, "fig4_intervention_margins"),
        layout.run_figure(*run, "rho_vs_seeds"),
        layout.run_figure(*run, "statistics_dots"),
        *[p for name in ["statistics", "seed_curve"] for p in layout.run_tables(*run, name)],
    ]


# Cluster requests, from each job's size (stereovar.resources). Account, partition and the
# GPU model stay out of the rules: they come from the profile (profiles/slurm*).


def batch_size(wildcards):
    """Seeds per view in the job's ``{batch}`` (1 for jobs without one)."""
    batch = getattr(wildcards, "batch", None)
    return len(batch_seeds(batch)) if batch else 1


def render_resources(n_views=2, spp=None, gpu=True, cpus=None, moments=False):
    """Memory, runtime and (with ``gpu``) GPU requests of a job rendering ``n_views`` views
    of each seed of its ``{batch}`` (one seed without one) at ``spp`` (the job's ``spp``
    wildcard when None); ``moments``: one view's two half renders (``spp`` samples in
    all) for the moments estimator."""

    def runtime(wildcards, attempt):
        return sizing.render_runtime(
            WIDTH,
            HEIGHT,
            int(wildcards.spp if spp is None else spp),
            n_views * batch_size(wildcards),
            samples_per_second=CLUSTER["render_samples_per_second"],
            attempt=attempt,
        )

    def mem_mb(wildcards, attempt):
        if moments:
            return sizing.moments_mem_mb(WIDTH, HEIGHT, attempt=attempt)
        return sizing.render_mem_mb(WIDTH, HEIGHT, batch=batch_size(wildcards), attempt=attempt)

    requests = {
        "mem_mb": mem_mb,
        "runtime": runtime,
        "cpus_per_task": CLUSTER["render_threads"] if cpus is None else cpus,
    }
    if gpu and CLUSTER["gpus_per_render"]:
        requests["gpu"] = CLUSTER["gpus_per_render"]
        if CLUSTER["gpu_model"]:
            requests["gpu_model"] = CLUSTER["gpu_model"]
    return requests


def analysis_resources(images, n_reads):
    """Memory and runtime requests of an analysis job holding ``images`` images at once and
    reading ``n_reads`` renders."""
    return {
        "mem_mb": lambda wildcards, attempt: sizing.analysis_mem_mb(
            WIDTH, HEIGHT, images, attempt=attempt
        ),
        "runtime": lambda wildcards, attempt: sizing.analysis_runtime(
            WIDTH, HEIGHT, n_reads, attempt=attempt
        ),
    }


def intervention_resources():
    """Memory and runtime requests of one scene's intervention (D estimated before the
    ground truth exists: the configured one, else 5% of the width plus the margin)."""
    iv = config["intervention"]
    d = iv["max_disparity"] or math.ceil(0.05 * WIDTH) + iv["disparity_margin"]
    return {
        "mem_mb": lambda wildcards, attempt: sizing.analysis_mem_mb(
            WIDTH, HEIGHT, 24, attempt=attempt
        ),
        "runtime": lambda wildcards, attempt: sizing.intervention_runtime(
            WIDTH, HEIGHT, INTERVENTION_N_SEEDS, d + 1, attempt=attempt
        ),
        "cpus_per_task": 2,
    }


def snakemake_arguments():
    """This run's ``--configfile`` and ``--config`` options, as a shell fragment: the
    rebuild commands printed for a damaged store repeat them."""
    parts = [f"--configfile {shlex.quote(str(f))}" for f in workflow.overwrite_configfiles]
    overrides = workflow.config_settings.config or {}
    if overrides:
        entries = []
        for key, value in overrides.items():
            text = yaml.safe_dump(value, default_flow_style=True, width=10**6).strip()
            entries.append(shlex.quote(f"{key}={text.removesuffix('...').strip()}"))
        parts.append("--config " + " ".join(entries))
    return " ".join(parts)


# Repeated by the rebuild command of any damaged-store message of this run's jobs.
set_rerun_arguments(snakemake_arguments())

# A run killed on this host leaves its lock behind; the same command then resumes instead
# of asking for --unlock (stereovar.preflight.stale_lock: only a lock whose run is gone).
if workflow.is_main_process and clear_stale_lock(STATE_DIR):
    print("stereovar: removed the lock of an earlier run that was killed", file=sys.stderr)


def render_stores(renderer=None):
    """Every render and moment store the configured tables pool (all scenes, SPPs and
    batches, and the intervention's seeds) of ``renderer`` (default: every renderer run)."""
    if renderer is not None:
        return configured_stores(renderer_config(renderer))
    if AUDIT:
        return configured_stores(config)
    return [p for r in RENDERER_RUNS for p in configured_stores(renderer_config(r))]


RENDERER_RULES = {"render", "ground_truth", "preview"}


def preflight():
    """Checks made in ``onstart``, after the DAG is known and before any job (and so before
    Snakemake deletes any output): the back end that this machine's jobs would use is
    available, and the renders that the tables pool come from one back end
    (:func:`stereovar.preflight.check_backends`). A cluster run's jobs resolve the back end
    on their own nodes; their renders are checked by the jobs that pool them."""
    from stereovar.renderers import get_renderer as renderer_named

    mark_run(STATE_DIR)
    jobs = list(workflow.dag.needrun_jobs())
    outputs = {str(f) for job in jobs for f in job.output}
    rules = {job.rule.name for job in jobs}
    with exit_with_one_line():
        for renderer in [get_renderer()] if AUDIT else RENDERER_RUNS:
            kept = stored_backends(p for p in render_stores(renderer) if p not in outputs)
            renders = {
                job.rule.name
                for job in jobs
                if job.wildcards.get("renderer", renderer) == renderer
            }
            planned = None
            if workflow.local_exec and renders & RENDERER_RULES:
                planned = renderer_named(renderer).backend(config["render"]["variant"])
            check_backends(
                kept,
                planned if "render" in renders else None,
                allow_mixed=config["render"]["allow_mixed_backends"],
            )
    # an audit that imports a frame again or rebuilds its verdict: the old verdict is set
    # aside (results/audit/<name>/previous/) until the new one is written
    if AUDIT and rules & {"audit_import", "audit_verdict"}:
        set_aside_verdict(AUDIT["name"])


def warn_if_report_is_stale(summary=layout.summary_json()):
    """With ``--report``: warn when the stored results were made with another config (the
    report shows whatever tables exist, whichever config made them)."""
    if not any(a == "--report" or a.startswith("--report=") for a in sys.argv):
        return
    path = Path(summary)
    stored = json.loads(path.read_text()).get("config_digest") if path.is_file() else None
    if stored != config_digest(dict(config)):
        why = "there is none yet" if stored is None else "it was made with another config"
        print(
            f"stereovar: warning: {summary} does not match this config ({why}); the report "
            "would show older tables: run `snakemake -j2 all` with the same options first",
            file=sys.stderr,
        )


warn_if_report_is_stale()


def print_summary():
    """At the end of a successful run: the claims table (Markdown), or an audit's verdict
    summary lines, when they exist."""
    if AUDIT:
        summary = Path(audit_paths(AUDIT["name"])["summary"])
        if summary.exists():
            print("\n" + "\n".join(json.loads(summary.read_text())["summary"]))
        return
    table = Path(layout.claims_tables()[layout.TABLE_FORMATS.index("md")])
    if table.exists():
        print(f"\n{table}:\n\n{table.read_text()}")


# Mitigations (stereovar.mitigations): each row of results/tables/mitigations.* is a source
# key (the renderer, or the renderer and a transform or seed policy), an SPP and its scenes,
# measured by the seeds estimator, the intervention and the per-scene mitigation rows.
MITIGATIONS = config["mitigations"]
if AUDIT:
    with exit_with_one_line():
        MITIGATION_RUNS = audit_mitigation_runs(config) if AUDIT.get("mitigations") else []
else:
    MITIGATION_RUNS = mitigation_runs(config) if MITIGATIONS["names"] else []
MITIGATION_SOURCE = get_renderer()  # the renderer, or the audit's source
MITIGATION_TABLES = layout.mitigation_tables(MITIGATION_SOURCE)
MITIGATION_HEADLINE = layout.mitigation_headline_tables(MITIGATION_SOURCE)
MITIGATION_FIGURE = layout.mitigation_figure(MITIGATION_SOURCE)
REFERENCE_SPP = MITIGATIONS["reference_spp"]
AUX_SPP = MITIGATIONS["aux_spp"]



def reference_from_moments(source):
    """Whether a source's converged reference is a moments render of each view at
    ``mitigations.reference_spp`` (a renderer with sample moments, rendering with the
    independent sampler and the box filter), else a split-half reference of its own renders
    (:func:`stereovar.statistics.utility.split_half_quality`: audits, Cycles)."""
    from stereovar.config import moments_settings_error

    render = config["render"]
    return (
        source in RENDERERS
        and RENDERERS.get(source).sample_moments
        and moments_settings_error(render["sampler"], render["rfilter"]) is None
    )


def source_aux_passes(source):
    """The auxiliary passes a source gives (a renderer's ``aux_passes``; an audit none)."""
    if source in RENDERERS:
        return RENDERERS.get(source).aux_passes
    return ()


def transform_inputs(wildcards):
    """Every render store of the wildcards' view of the source (all seeds: the seed mean and
    variance are over them) and, when the transform reads albedo or normal and the source
    renders them, the view's auxiliary passes."""
    inputs = {
        "renders": seed_stores(run_config(wildcards.renderer), wildcards.scene, wildcards.spp)[
            wildcards.view
        ]
    }
    t = get_transform(wildcards.transform)
    wants = {"albedo", "normal"} & {*t.reads, *t.optional_reads}
    if wants and wants <= set(source_aux_passes(wildcards.renderer)):
        inputs["aux"] = layout.aux_store(wildcards.renderer, wildcards.scene, wildcards.view)
    return inputs


def transform_options(wildcards):
    """The options of the wildcards' transform that the config sets: the camera model of
    ``controls.sensor`` (gain, read noise) for the transforms that add or model camera noise."""
    import inspect

    accepted = inspect.signature(get_transform(wildcards.transform).apply).parameters
    sensor = config["controls"]["sensor"]
    offered = {"gain": sensor["gain"], "read_noise": sensor["read_noise"]}
    return {k: v for k, v in offered.items() if k in accepted}


def mitigation_scene_inputs(wildcards):
    """One scene's render stores of the wildcards' source key at its SPP, its ground truth
    and each view's converged reference (:func:`reference_from_moments`)."""
    source, _ = layout.split_source_key(wildcards.renderer)
    if reference_from_moments(source):
        reference = {
            view: layout.moment_store(source, wildcards.scene, view, REFERENCE_SPP)
            for view in VIEWS
        }
    else:
        reference = seed_stores(run_config(source), wildcards.scene, wildcards.spp)
    return {
        **seed_stores(run_config(wildcards.renderer), wildcards.scene, wildcards.spp),
        "ground_truth": ground_truth_input(wildcards),
        **{f"reference_{view}": paths for view, paths in reference.items()},
    }


def mitigation_files(run):
    """The per-scene files one mitigation row is summarised from."""
    estimator = MITIGATION_ESTIMATOR
    files = {
        "correlation": [
            layout.correlation_rows(run.source, estimator, s, run.spp, run.transform)
            for s in run.scenes
        ],
        "scene_rows": [
            layout.mitigation_rows(run.source, estimator, s, run.spp, run.transform)
            for s in run.scenes
        ],
        # the intervention runs at intervention.spp only
        "intervention": (
            [layout.intervention_metrics(run.source, estimator, s, run.transform) for s in run.scenes]
            if run.spp == INTERVENTION_SPP
            else []
        ),
    }
    return files


def mitigation_table_inputs(wildcards):
    """Every mitigation row's per-scene files, and the calibration's matched nulls."""
    return {
        "files": [
            p for run in MITIGATION_RUNS for paths in mitigation_files(run).values() for p in paths
        ],
        "nulls": layout.calibration_nulls(MITIGATION_SOURCE),
        "calibration": calibration_table_inputs(),
    }


def image_cost(run):
    """Samples per pixel behind one mitigated image (``render_spp``: N x SPP when the
    transform reads the seed mean or variance, which average the N renders) and the SPP of
    the auxiliary pass it reads once per view (``aux_spp``; 0 without one)."""
    render_spp, aux_spp = run.spp, 0
    if run.mitigation.kind == "transform":
        t = get_transform(run.transform)
        if {"seed_mean", "seed_var"} & set(t.reads):
            render_spp *= N_SEEDS
        wants = {"albedo", "normal"} & {*t.reads, *t.optional_reads}
        if wants and wants <= set(source_aux_passes(run.source)):
            aux_spp = AUX_SPP
    return {"render_spp": render_spp, "aux_spp": aux_spp}


def mitigation_table_params():
    """What the table job needs per row beside the files: name, kind, description, SPP."""
    return [
        {
            "mitigation": run.name,
            "kind": run.mitigation.kind,
            "description": run.mitigation.description,
            "spp": run.spp,
            "calibration_transform": run.transform if run.mitigation.kind == "transform" else "none",
            **image_cost(run),
            **mitigation_files(run),
        }
        for run in MITIGATION_RUNS
    ]


def mitigation_targets():
    """`snakemake mitigations`: the mitigation table and its trade-off figure, the run's or
    the audit's (nothing when ``mitigations.names``, or ``audit.mitigations``, is empty)."""
    if not MITIGATION_RUNS:
        return []
    return [*MITIGATION_TABLES, *MITIGATION_HEADLINE, MITIGATION_FIGURE]


# The calibration (stereovar.calibration): each scene of the run's source, at the main SPP,
# through "none" and every store transform of the mitigation rows.
from stereovar.calibration.replicates import reads_seed_mean

CALIBRATION_TRANSFORMS = [
    "none",
    *dict.fromkeys(r.transform for r in MITIGATION_RUNS if r.mitigation.kind == "transform"),
]
# The variance store it is drawn like: the seeds estimator's where the mitigation rows (or an
# audit) have one, else the run's own estimator's (a moments run renders no seeds for it).
CALIBRATION_ESTIMATOR = (
    MITIGATION_ESTIMATOR if (AUDIT or MITIGATION_RUNS) else get_estimator()
)
# The frames per view of every replicate: N seeds, or the moments estimator's samples.
CALIBRATION_DRAWS = N_SEEDS if CALIBRATION_ESTIMATOR == "seeds" else MAIN_SPP
CALIBRATION_TABLES = layout.calibration_tables(MITIGATION_SOURCE)
CALIBRATION_NULLS = layout.calibration_nulls(MITIGATION_SOURCE)
CALIBRATION_FIGURE = layout.calibration_figure(MITIGATION_SOURCE)


def calibration_options():
    """Each calibrated transform's options, as the transform rule passes them."""
    return {
        t: transform_options(SimpleNamespace(transform=t))
        for t in CALIBRATION_TRANSFORMS
        if t != "none"
    }


def calibration_resources():
    """Memory (every frame of both views, the transformed stacks and the renders: 4N + 16
    images, N the frames drawn per view) and runtime
    (:func:`stereovar.resources.calibration_runtime`) of one scene's calibration."""
    cal = config["calibration"]
    denoisers = [
        t for t in CALIBRATION_TRANSFORMS[1:] if get_transform(t).expensive
    ]
    runtime = lambda wildcards, attempt: sizing.calibration_runtime(
        WIDTH,
        HEIGHT,
        CALIBRATION_DRAWS,
        replicates=int(cal["replicates"]),
        designs=2 + len(cal["strengths"]),
        transforms=len(CALIBRATION_TRANSFORMS) - len(denoisers),
        denoised_replicates=int(cal["denoised_replicates"]),
        denoisers=len(denoisers),
        attempt=attempt,
    )
    return {
        **analysis_resources(images=4 * CALIBRATION_DRAWS + 16, n_reads=2 * CALIBRATION_DRAWS),
        "runtime": runtime,
    }


def calibration_scene_inputs(wildcards):
    """One scene's seeds variance store and ground truth, and each view's auxiliary passes
    when a calibrated transform reads them and the source renders them."""
    source = wildcards.renderer
    inputs = {
        "variance": layout.variance_store(
            source, wildcards.estimator, wildcards.scene, wildcards.spp
        ),
        "ground_truth": ground_truth_input(wildcards),
    }
    wants = set()
    for t in CALIBRATION_TRANSFORMS[1:]:
        transform = get_transform(t)
        wants |= {"albedo", "normal"} & {*transform.reads, *transform.optional_reads}
    if wants and wants <= set(source_aux_passes(source)):
        for view in VIEWS:
            inputs[f"aux_{view}"] = layout.aux_store(source, wildcards.scene, view)
    if wildcards.estimator == "seeds" and any(reads_seed_mean(t) for t in CALIBRATION_TRANSFORMS):
        stores = seed_stores(run_config(source), wildcards.scene, wildcards.spp)
        inputs.update({f"renders_{view}": paths for view, paths in stores.items()})
    return inputs


def calibration_table_inputs():
    """Every scene's calibration replicates."""
    return [
        layout.calibration_rows(MITIGATION_SOURCE, CALIBRATION_ESTIMATOR, s, MAIN_SPP)
        for s in SCENES
    ]


def calibration_targets():
    """`snakemake calibration`: the calibration table, its matched nulls and figure."""
    return [*CALIBRATION_TABLES, CALIBRATION_NULLS, CALIBRATION_FIGURE]


# The learned probe (stereovar.probe): per architecture, one network per training condition,
# variant (the network and its cue-blind twin), fold and training seed; one test job per
# condition, architecture and fold scores the condition's networks, their twins and the
# control's on the fold's held-out scenes under the condition. A planted condition reads the
# renders of `none` with a planted cue of known strength (probe/planted.json).
from stereovar.probe.conditions import CONTROL as PROBE_CONTROL
from stereovar.probe.conditions import MAIN as PROBE_MAIN
from stereovar.probe.architectures import architecture
from stereovar.probe.conditions import check_probe, probe_conditions

PROBE = config["probe"]
PROBE_WANTED = not AUDIT or bool(AUDIT.get("probe"))
with exit_with_one_line():
    PROBE_CONDITIONS = (
        {c.name: c for c in probe_conditions(config)} if PROBE_WANTED else {}
    )
PROBE_ARCHS = list(dict.fromkeys(PROBE["architectures"]))
PROBE_FOLDS = int(PROBE["folds"])
PROBE_SEEDS = list(range(int(PROBE["train_seeds"])))
PROBE_SOURCE = get_renderer()
PROBE_TABLES = layout.probe_tables(PROBE_SOURCE)
PROBE_TRAINING_TABLES = layout.probe_training_tables(PROBE_SOURCE)
PROBE_FIGURE = layout.probe_figure(PROBE_SOURCE)
PROBE_VERDICT = layout.probe_verdict(PROBE_SOURCE)
PROBE_PLANTED = layout.probe_planted(PROBE_SOURCE)
PROBE_ANY_PLANTED = any(c.planted for c in PROBE_CONDITIONS.values())
PROBE_TWINNED = [name for name, c in PROBE_CONDITIONS.items() if c.twin]
# wildcard patterns: the conditions, those with a twin, the architectures
PROBE_CONDITION_PATTERN = "|".join(map(re.escape, PROBE_CONDITIONS)) or "none"
PROBE_TWINNED_PATTERN = "|".join(map(re.escape, PROBE_TWINNED)) or "none"
PROBE_ARCH_PATTERN = "|".join(PROBE_ARCHS) or "mccnn"


def probe_folds():
    """(training scenes, held-out scenes) of every fold; a config error when the scenes
    cannot fill ``probe.folds`` folds."""
    from stereovar.probe.experiment import fold_scenes
    from stereovar.errors import ConfigError

    try:
        return fold_scenes(SCENES, PROBE_FOLDS)
    except ValueError as err:
        raise ConfigError(f"config key 'probe.folds': {err}") from None


def probe_stores(key, spp, scenes):
    """Render stores of each view and the ground truth of ``scenes`` under source key ``key``
    at ``spp``, named ``left_{scene}``, ``right_{scene}`` and ``gt_{scene}``."""
    stores = {}
    for scene in scenes:
        views = seed_stores(run_config(key), scene, spp)
        stores.update({f"{view}_{scene}": views[view] for view in VIEWS})
        stores[f"gt_{scene}"] = ground_truth_store(key, scene)
    return stores


def probe_condition_stores(name, scenes):
    """The stores condition ``name`` reads for ``scenes`` (a planted condition: ``none``'s
    renders and the planted settings, ``planted``)."""
    condition = PROBE_CONDITIONS[name]
    run = condition.run
    stores = probe_stores(layout.source_key(run.source, run.transform), run.spp, scenes)
    if condition.planted:
        stores["planted"] = PROBE_PLANTED
    return stores


def probe_checked():
    """The probe's settings that fail before any job (too few renders per view, a GPU that
    PyTorch cannot use), checked when the plan first holds a probe job: one line and exit."""
    with exit_with_one_line():
        check_probe(config, N_SEEDS)


def probe_planted_inputs(wildcards):
    """`none`'s renders of every scene, whose strength and camera laws set the planted cue."""
    probe_checked()
    return probe_condition_stores("none", SCENES)


def probe_train_inputs(wildcards):
    """The training scenes of the wildcards' fold under its condition."""
    probe_checked()
    return probe_condition_stores(wildcards.condition, probe_folds()[int(wildcards.fold)][0])


def probe_networks(condition, arch, fold):
    """The networks one test job scores: the condition's, its twins' and the control's."""
    variants = [(condition, v) for v in PROBE_CONDITIONS[condition].variants]
    if condition != PROBE_CONTROL:
        variants.append((PROBE_CONTROL, PROBE_MAIN))
    return [
        layout.probe_network(PROBE_SOURCE, c, arch, v, fold, j)
        for c, v in variants
        for j in PROBE_SEEDS
    ]


def probe_test_inputs(wildcards):
    """The held-out scenes of the wildcards' fold under its condition, and the networks."""
    fold = int(wildcards.fold)
    return {
        **probe_condition_stores(wildcards.condition, probe_folds()[fold][1]),
        "networks": probe_networks(wildcards.condition, wildcards.arch, fold),
    }


def probe_tile_files():
    """Every test job's tile table."""
    return [
        layout.probe_tiles(PROBE_SOURCE, c, a, f)
        for c in PROBE_CONDITIONS
        for a in PROBE_ARCHS
        for f in range(PROBE_FOLDS)
    ]


def probe_network_files():
    """Every network of the probe."""
    return sorted(
        {
            path
            for c in PROBE_CONDITIONS
            for a in PROBE_ARCHS
            for f in range(PROBE_FOLDS)
            for path in probe_networks(c, a, f)
        }
    )


def probe_table_inputs(wildcards):
    """Every tile table and network, and the planted settings where a planted cue runs."""
    inputs = {"tiles": probe_tile_files(), "networks": probe_network_files()}
    if PROBE_ANY_PLANTED:
        inputs["planted"] = PROBE_PLANTED
    return inputs


def probe_model_stores(wildcards=None):
    """Every frame's render stores of each view and its ground truth (``left_{scene}``,
    ``right_{scene}``, ``gt_{scene}``): the audit's imported frames, or the run's scenes."""
    return probe_stores(get_renderer(), MAIN_SPP, SCENES)


def probe_targets():
    """`snakemake probe`: the probe table, figure and verdict (nothing for an audit without
    ``audit.probe: true``)."""
    if not PROBE_CONDITIONS:
        return []
    return [*PROBE_TABLES, *PROBE_TRAINING_TABLES, PROBE_FIGURE, PROBE_VERDICT]


def probe_if_run():
    """The probe's outputs when they exist (they are not part of `all`; a run that made them
    has its report and summary include them)."""
    targets = probe_targets()
    return targets if targets and all(Path(p).exists() for p in targets) else []


def generators_if_run():
    """The generator tables and figure when they exist (`snakemake generators` is not part
    of `all`; a run that made them has its results page show them)."""
    targets = [*layout.generator_tables(), layout.generator_figure()]
    return targets if all(Path(p).exists() for p in targets) else []


# The results page (results/index.html, made in claims.smk; stereovar.pages.results): the
# claims, the headline with its controls and every figure and table of `all`, each figure
# with its report caption.
PAGE_CAPTIONS = {
    "fig1_teaser": "fig1_teaser.rst",
    "fig2_rho_vs_spp": "fig2_rho_vs_spp.rst",
    "fig3_material_scatter": "fig3_material_scatter.rst",
    "fig4_intervention_margins": "fig4_intervention_margins.rst",
    "rho_vs_seeds": "fig_rho_vs_seeds.rst",
    "statistics_dots": "fig_statistics_dots.rst",
    "cross_renderer": "fig_cross_renderer.rst",
    "mitigations": "mitigations_figure.rst",
    "probe": "probe_figure.rst",
    "generators": "generators.rst",
    "calibration": "calibration.rst",
    "claims": "claims.rst",
    "workflow": "workflow.rst",
}


def page_captions():
    """The results page's captions by figure name (and ``claims``, ``workflow``): the
    report's captions with their Jinja filled from this config, as the report fills them
    (:func:`stereovar.pages.captions.render_caption`)."""
    from stereovar.pages.captions import render_caption

    return {
        name: render_caption(
            Path(workflow.source_path(f"../report/{rst}")).read_text(encoding="utf-8"), config
        )
        for name, rst in PAGE_CAPTIONS.items()
    }


def page_results():
    """(figures, tables) of the results page: every figure (PNG) and every table file of
    `all`; the mitigations' and the probe's figures are their sections' inputs."""
    own = {MITIGATION_FIGURE, PROBE_FIGURE, layout.results_page()}
    targets = [Path(p) for p in all_targets() if p not in own]
    figures = [str(p) for p in targets if p.parent.name == "figures" and p.suffix == ".png"]
    tables = [
        str(p)
        for p in targets
        if p.parent.name == "tables" and p.suffix[1:] in layout.TABLE_FORMATS
    ]
    return figures, tables


# Generator profiles (stereovar.generators; rules in generators.smk): each profile as rendered
# at the budget (generators.spp), its render stores and the matched null's inputs.
from stereovar.errors import ConfigError
from stereovar.generators import PAPER, PROFILES, generator_profiles
from stereovar.jobs.generators import profile_matched_transform
from stereovar.renderers.cycles.settings import cycles_options

GENERATORS = config["generators"]
GENERATOR_SPP = int(GENERATORS["spp"])
GENERATOR_SCENES = list(GENERATORS["scenes"] or SCENES[:2])
# an audit renders nothing: its profiles are never planned
GENERATOR_ROWS = {}
if not AUDIT:
    with exit_with_one_line():
        GENERATOR_ROWS = {p.name: p for p in generator_profiles(config)}
        _outside = [s for s in GENERATOR_SCENES if s not in SCENES]
        if _outside:
            raise ConfigError(
                f"config key 'generators.scenes': {', '.join(_outside)} not in 'scenes'; "
                "list only scenes of the run"
            )


def generator_calibration_inputs(wildcards):
    """The variance store the profile's matched null is drawn like and the ground truth: the
    profile's own, or for a profile whose denoiser runs the paper row's (the raw renders'
    noise level, which the null then passes through OIDN with each view's albedo and normal
    from Mitsuba's auxiliary pass of the same scene)."""
    profile = GENERATOR_ROWS[wildcards.profile]
    matched = profile_matched_transform(profile.cycles)
    drawn_like = PAPER if matched == "denoise" else profile.name
    inputs = {
        "variance": layout.variance_store(
            layout.generator_source(drawn_like), "seeds", wildcards.scene, wildcards.spp
        ),
        "ground_truth": layout.traced_ground_truth(wildcards.scene),
    }
    if matched == "denoise":
        for view in VIEWS:
            inputs[f"aux_{view}"] = layout.aux_store("mitsuba", wildcards.scene, view)
    return inputs


def generator_table_params():
    """Per profile: the profile as rendered and its per-scene files."""
    runs = []
    for name, p in GENERATOR_ROWS.items():
        source = layout.generator_source(name)
        runs.append(
            {
                "profile": name,
                "spp": p.spp,
                "generator_spp": round(p.spp / p.scale),
                "scale": p.scale,
                "cycles": p.cycles,
                "calibration_transform": profile_matched_transform(p.cycles),
                "correlation": [
                    layout.correlation_rows(source, "seeds", s, GENERATOR_SPP)
                    for s in GENERATOR_SCENES
                ],
                "scene_rows": [
                    layout.mitigation_rows(source, "seeds", s, GENERATOR_SPP)
                    for s in GENERATOR_SCENES
                ],
                "calibration": [
                    layout.generator_calibration_rows(name, s, GENERATOR_SPP)
                    for s in GENERATOR_SCENES
                ],
            }
        )
    return runs


def generator_targets():
    """`snakemake generators`: the generator table and its figure."""
    return [*layout.generator_tables(), layout.generator_figure()]
