"""An audit as a workflow run: import, the run's config, and its targets.

``workflow/rules/common.smk`` calls :func:`prepare_audit` when the config has an ``audit:``
section, then replaces the run's scenes, renderer, N and SPP with the audit's
(:func:`audit_run_config`), so every rule downstream of the renders (Eq. 1-3, the controls,
the intervention, the tables) runs unchanged on the imported stores; ``all`` then builds
:func:`audit_targets`, ending in the verdict page.
"""

from __future__ import annotations

import sys

from ..experiment import audit_source, ground_truth_store, run_prefix
from ..io.images import image_size
from ..rig import VIEWS
from .importer import ImportReport, audit_spp, check_settings, frame_stores, import_audit
from .layout import Discovery, discover

TABLE_FORMATS = ("csv", "md", "tex", "html")


IMPORT_MODES = ("import", "plan", "discover")
"""What :func:`prepare_audit` does with an audit's files: import them; only find what an
import would do (a dry run: files are hashed, nothing is written); only discover them."""

READ_ONLY_OPTIONS = frozenset(
    {
        "--lint",
        "--list-rules",
        "--list",
        "-l",
        "--list-target-rules",
        "--lt",
        "--list-resources",
        "--dag",
        "--rulegraph",
        "--filegraph",
        "--d3dag",
        "--summary",
        "-S",
        "--detailed-summary",
        "-D",
        "--list-changes",
        "--lc",
        "--list-input-changes",
        "--li",
        "--list-params-changes",
        "--lp",
        "--list-untracked",
        "--lu",
        "--report",
        "--containerize",
        "--print-compilation",
        "--generate-unit-tests",
        "--archive",
        "--unlock",
        "--cleanup-metadata",
        "--cm",
        "--cleanup-shadow",
        "--conda-create-envs-only",
        "--conda-cleanup-envs",
        "--list-conda-envs",
        "--container-cleanup-images",
        "--delete-all-output",
        "--delete-temp-output",
    }
)
"""Snakemake options whose command reads the workflow and runs no job."""

DRY_RUN_OPTIONS = frozenset({"-n", "--dry-run", "--dryrun"})
"""Snakemake's dry-run options (for Snakemake versions whose settings do not say)."""


def import_mode(*, main_process: bool, dry_run: bool, argv=()) -> str:
    """How a workflow that reads an ``audit:`` config treats its files (:data:`IMPORT_MODES`).

    Only the main process of a run that executes jobs imports. A dry run, or a command that
    only reads the workflow (``--lint``, ``--summary``, ``--dag``, a report, ...), plans:
    it reports what an import would do and writes nothing. A cluster job, whose stores the
    main process imported, only discovers the files.

    Parameters
    ----------
    main_process : bool, keyword-only
        Snakemake's ``workflow.is_main_process``.
    dry_run : bool, keyword-only
        Snakemake's ``workflow.output_settings.dryrun``.
    argv : sequence of str, keyword-only
        The command line's arguments (``sys.argv[1:]``): the options of
        :data:`READ_ONLY_OPTIONS` and :data:`DRY_RUN_OPTIONS` (``-n`` also within a group
        of short flags such as ``-np``); ``--report-after-run`` runs the jobs first.

    Returns
    -------
    str
        ``"import"``, ``"plan"`` or ``"discover"``.
    """
    if not main_process:
        return "discover"
    options = {a.split("=", 1)[0] for a in argv if a.startswith("-")}
    flags = {
        f"-{c}" for a in argv if len(a) > 1 and a[0] == "-" and a[1:].isalpha() for c in a[1:]
    }
    given = options | flags
    reading = given & READ_ONLY_OPTIONS and "--report-after-run" not in options
    if dry_run or reading or given & DRY_RUN_OPTIONS:
        return "plan"
    return "import"


def prepare_audit(settings: dict, *, mode: str = "import", stream=None) -> ImportReport:
    """Import the audit's files, or plan the import, or only discover them
    (:data:`IMPORT_MODES`, :func:`import_mode`), and print the import's summary lines to
    ``stream`` (stderr).

    Returns
    -------
    ImportReport
        Its ``discovery`` (the frames); with ``mode="discover"`` no frame is listed.
    """
    if mode not in IMPORT_MODES:
        raise ValueError(f"unknown import mode {mode!r}; use one of {', '.join(IMPORT_MODES)}")
    check_settings(settings)
    if mode == "discover":
        return ImportReport(settings["name"], discover(settings), [])
    report = import_audit(settings, dry_run=mode == "plan")
    for line in report.lines():
        print(f"stereovar: {line}", file=stream or sys.stderr)
    return report


def planned_stores(settings: dict, report: ImportReport) -> dict:
    """The stores a dry run's import would write (re-import), each with the files it is
    imported from; empty for a report that is not a dry run's.

    A run imports before it builds its jobs; a dry run imports nothing, so the workflow
    makes these, and :func:`planned_marker`, the outputs of a rule (``audit_import``) that
    only a dry run has, and the dry run lists the jobs that would read them.
    """
    if not report.dry_run:
        return {}
    pending = {f.name for f in report.frames if f.imported}
    out = {}
    for frame in report.discovery.frames:
        if frame.name in pending:
            files = [str(p) for p in frame.files()]
            for store in frame_stores(settings, frame.name, frame.n_seeds).values():
                out[store] = files
    return out


def planned_marker(settings: dict) -> str:
    """A path no run writes, ``results/audit/{name}/.import-planned``: an output of a dry
    run's ``audit_import`` that ``all`` asks for, so the dry run lists the import (and the
    jobs that read its stores) even when the changed files kept their time stamps."""
    return f"results/{audit_source(settings['name'])}/.import-planned"


def audit_run_config(config: dict, discovery: Discovery) -> dict:
    """The config keys an audit replaces: ``scenes`` (its frames), ``resolution``, the rig's
    convention, and ``render`` (source ``audit/{name}``, the seeds estimator, N and SPP
    from the files, one store per view and frame, no render cache); the intervention uses
    all N seeds."""
    settings = config["audit"]
    frames = [f.name for f in discovery.frames]
    n, spp = discovery.n_seeds, audit_spp(settings)
    height, width = image_size(next(iter(discovery.frames[0].renders[VIEWS[0]].values())))
    return {
        "scenes": frames,
        "resolution": {"width": width, "height": height},
        "rig": {**config["rig"], "convention": settings.get("convention") or "conventional"},
        "render": {
            **config["render"],
            "renderer": audit_source(settings["name"]),
            "estimator": "seeds",
            "n_seeds": n,
            "seeds_per_job": n,
            "spp": spp,
            "spp_sweep": {"scene": frames[0], "spp": [spp]},
            "cache": None,
        },
        "intervention": {**config["intervention"], "n_seeds": None, "spp": None},
    }


def audit_paths(name: str) -> dict:
    """The verdict page, its summary and the per-frame teaser pattern of an audit."""
    base = f"results/{audit_source(name)}"
    return {
        "verdict_md": f"{base}/verdict.md",
        "verdict_html": f"{base}/verdict.html",
        "summary": f"{base}/summary.json",
        "teaser": base + "/figures/teaser_{scene}.png",
    }


def audit_targets(config: dict) -> list[str]:
    """What ``all`` builds for an audit: the imported ground truth, every frame's
    correlation rows and intervention, the pooled tables and figures, one teaser per frame,
    and the verdict page with its summary."""
    source = config["render"]["renderer"]
    spp = config["render"]["spp"]
    run = run_prefix(source, "seeds")
    frames = list(config["scenes"])
    paths = audit_paths(config["audit"]["name"])
    tables = ["statistics", "seed_curve", "cross_scene", "intervention"]
    return [
        *[ground_truth_store(source, f) for f in frames],
        *[f"{run}/correlation/{f}/spp{spp}.csv" for f in frames],
        *[f"{run}/intervention/{f}.csv" for f in frames],
        *[f"{run}/tables/{t}.{ext}" for t in tables for ext in TABLE_FORMATS],
        f"{run}/figures/statistics_dots.png",
        f"{run}/figures/rho_vs_seeds.png",
        *[paths["teaser"].format(scene=f) for f in frames],
        paths["verdict_md"],
        paths["verdict_html"],
        paths["summary"],
    ]
