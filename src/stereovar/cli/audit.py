"""``stereovar audit`` (renders made elsewhere, checked, run through the workflow, the
verdict printed) and ``stereovar export`` (the run's renders and ground truth as files an
audit reads)."""

from __future__ import annotations

import argparse
import sys

from ..errors import StereovarError
from ..progress import JOB_LINE
from ..stages import stage_list
from .monitor import _Run, log_line
from .snakemake import (
    _MONITOR,
    PROG,
    _hold_results,
    _new_log,
    _project_root,
    _run_snakemake,
    _warn_unlocked,
    _workflow_config,
    say,
)

#: The exit status of ``stereovar audit --fail-on LEVEL`` when the verdict is at or past
#: ``LEVEL``: distinct from a usage error or a refused input (2) and from a failed Snakemake
#: run (its own status, 1).
FAIL_ON_STATUS = 3

#: The verdict's traffic lights (``light`` of the audit's ``summary.json``), least severe first;
#: ``--fail-on`` takes the two that can fail a pipeline.
SEVERITY = ("green", "amber", "red")
FAIL_ON_LEVELS = SEVERITY[1:]


def verdict_fails(light: str, level: str | None) -> bool:
    """Whether an audit's verdict fails the gate ``--fail-on level``: its light is ``level``
    or more severe (:data:`SEVERITY`). A light the gate does not know fails it too, so that a
    verdict it cannot read never passes a pipeline; no level, no gate.

    Parameters
    ----------
    light : str
        The verdict's ``light`` (``summary.json``): ``"green"``, ``"amber"`` or ``"red"``.
    level : str or None
        ``"amber"`` (fails on amber and red), ``"red"`` (fails on red only) or None.

    Returns
    -------
    bool

    Examples
    --------
    >>> verdict_fails("amber", "amber"), verdict_fails("amber", "red")
    (True, False)
    >>> verdict_fails("red", None)
    False
    """
    if level is None:
        return False
    if level not in FAIL_ON_LEVELS:
        raise ValueError(f"--fail-on takes {' or '.join(FAIL_ON_LEVELS)}, not {level!r}")
    if light not in SEVERITY:
        return True
    return SEVERITY.index(light) >= SEVERITY.index(level)


def _audit_log(root, name: str):
    """A new file for the whole Snakemake output of one ``stereovar audit``,
    ``logs/audit/<name>/stereovar-audit-<time>.log`` under ``root`` (never one that exists)."""
    return _new_log(root / "logs" / "audit" / name, "stereovar-audit")


def _import_warnings(root, name: str, frames) -> list:
    """The ``warning:`` lines of the audit's import logs (rule ``audit_import``'s
    ``logs/audit/<name>/import/<frame>.log``), each once."""
    warnings = []
    for frame in frames:
        path = root / "logs" / "audit" / name / "import" / f"{frame}.log"
        try:
            lines = path.read_text(errors="replace").splitlines()
        except OSError:
            continue
        for line in lines:
            match = JOB_LINE.fullmatch(line)
            text = (match.group(2) if match else line).strip()
            if text.startswith("warning:"):
                text = text[len("warning:") :].strip()
                if text not in warnings:
                    warnings.append(text)
    return warnings


def _audit_preflight(root, config: dict, discovery) -> None:
    """The workflow's checks of an audit, made before Snakemake starts and before anything
    is written: the folders the run writes can be written, the disk has room for
    Snakemake's lock (:mod:`stereovar.preflight`), and the run config's mitigations and
    memory (:func:`stereovar.audit.run.check_audit_run`), and every file's header
    (:func:`stereovar.audit.run.check_headers`); one line for the first problem."""
    from ..audit.run import audit_run_config, check_audit_run, check_headers
    from ..preflight import WRITTEN_FOLDERS, check_free_space, check_writable

    check_writable([root / d for d in WRITTEN_FOLDERS])
    check_free_space(root)
    check_audit_run({**config, **audit_run_config(config, discovery)}, discovery)
    check_headers(discovery)


def _cmd_audit(args: argparse.Namespace) -> int:
    from pathlib import Path

    from ..audit.run import discover_audit
    from ..schema import load_yaml

    if args.fail_on and args.import_only:  # the gate would pass without a verdict
        raise StereovarError(
            "--fail-on needs the verdict, which --import-only does not make; drop one of them"
        )
    root = _project_root()
    config = Path(args.config)
    if not config.is_file():
        raise StereovarError(f"{config}: no such config file; give the audit's YAML config")
    data = load_yaml(config, "audit config", error=StereovarError) or {}
    settings = data.get("audit") if isinstance(data, dict) else None
    if not isinstance(settings, dict):
        from ..links import docs_page

        raise StereovarError(
            f"{config}: no audit: section; add one (keys: name, renders, views, disparity, "
            f"convention; see {docs_page('audit')})"
        )
    # The whole config, as the workflow will see it, before any file is read; then the
    # files, found (not read) as the workflow finds them; the import is the workflow's (one
    # audit_import job per frame).
    workflow_config = _workflow_config(root, [config])
    settings = workflow_config["audit"]
    name = settings["name"]
    discovery = discover_audit(settings)
    _audit_preflight(root, workflow_config, discovery)
    # the audit's results are this command's until it ends: another audit of the same name
    # is refused here, before anything is written
    with _hold_results(root, workflow_config, args.command_line) as lock:
        _warn_unlocked(lock)
        return _audit(args, root, config, name, discovery)


def _audit(args, root, config, name: str, discovery) -> int:
    """Run the audit's workflow and say its verdict (``stereovar audit``, its inputs
    checked and its results held)."""
    import os
    from pathlib import Path

    from ..audit.run import PREVIOUS, audit_paths
    from ..audit.summary_schema import read_summary
    from ..layout import audit_source

    command = ["-j", str(args.cores), "all", "--configfile", str(config.resolve())]
    if args.import_only:
        command += ["--until", "audit_import"]
    log_path, log = _audit_log(root, name)
    log.close()  # Snakemake's output is appended to it as it comes
    shown_log = os.path.relpath(log_path)
    monitor = _Run(
        log_path,
        stages="audit",
        import_label=f"import: {discovery.summary()}",
        source=audit_source(name),
        verbose=args.verbose,
        command=f"{PROG} audit {args.config}",
    )
    token = _MONITOR.set(monitor)
    try:
        rc = _run_snakemake(command, root)
    finally:
        _MONITOR.reset(token)
    paths = audit_paths(name)
    summary = root / paths["summary"]
    # read through its schema: a gate never passes on a file it cannot read as a verdict
    verdict = read_summary(summary) if rc == 0 and not args.import_only else {}
    lines = verdict.get("summary", [])
    # the import's warnings, each once: those the verdict's summary does not already say
    for warning in _import_warnings(root, name, [f.name for f in discovery.frames]):
        if not any(warning in line for line in lines):
            say(f"warning: {warning}")
    if monitor.log_error:
        say(f"warning: the log ends early: {monitor.log_error}")
    if rc != 0:
        for message in monitor.errors(rc):
            say(f"{PROG}: error: {message}")
        previous = root / Path(paths["verdict_html"]).parent / PREVIOUS
        if not (root / paths["verdict_html"]).exists() and (previous / "verdict.html").exists():
            say(f"the verdict before this run, set aside as out of date: {previous}/")
        say(log_line(shown_log, monitor.job_logs()))
        return rc
    if args.import_only:
        records = root / Path(paths["summary"]).parent / "import"
        say(f"imported {name}: one record per frame in {records}", sys.stdout)
    else:
        say("\n".join(lines), sys.stdout)
        say(f"verdict page: {summary.parent / 'verdict.html'}", sys.stdout)
    say(f"log: {shown_log}", sys.stdout)
    if verdict_fails(verdict.get("light"), args.fail_on):
        say(f"{PROG}: --fail-on {args.fail_on}: {lines[0]}")
        return FAIL_ON_STATUS
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    from pathlib import Path

    from ..audit.export import check_export_targets, export_targets

    root = _project_root()
    files = [Path(f) for f in args.configfile or []]
    config = _workflow_config(root, files)
    targets = export_targets(config, args.format)
    check_export_targets(targets)  # a link or a stray folder would pass for an export
    options = ["-j", str(args.cores), "export", "--config", f"export={{formats: [{args.format}]}}"]
    for f in args.configfile or []:
        options[3:3] = ["--configfile", f]
    with _hold_results(root, config, args.command_line) as lock:
        _warn_unlocked(lock)
        rc = _run_snakemake(options, root)
        if rc != 0:
            return rc
        check_export_targets(targets)
    folder = Path(targets[0]).parent
    scenes = ", ".join(Path(t).name for t in targets)
    say(
        f"exported {len(targets)} scene{'s' * (len(targets) != 1)} to {folder}/ ({scenes}); "
        "each scene directory has an audit.yaml that audits it",
        sys.stdout,
    )
    return 0


def _register_audit(subparsers) -> None:
    audit = subparsers.add_parser(
        "audit",
        help="audit renders made elsewhere for the cross-view variance cue",
        description="Import N >= 2 renders per view of stereo frames and their ground truth "
        "(the audit: section of CONFIG), run every statistic, control and the intervention on "
        "them, and print the verdict's summary; the page is results/audit/<name>/verdict.html. "
        f"Prints one line per stage with jobs, in this order: {stage_list('audit')}; inside "
        "a long stage, its jobs done, the run's and an estimate of the time left; then the "
        "import's warnings. Snakemake's whole output goes to a log file whose path is printed "
        "(-v shows it live). A failed job: its one-line error, the log's path and a non-zero "
        "exit status.",
    )
    audit.add_argument("config", metavar="CONFIG", help="YAML config with an audit: section")
    audit.add_argument("-j", "--cores", type=int, default=2, help="cores (default 2)")
    audit.add_argument(
        "--import-only",
        action="store_true",
        help="run only the import jobs (one per frame: decode, check, sign-check, store)",
    )
    audit.add_argument(
        "--fail-on",
        choices=FAIL_ON_LEVELS,
        metavar="{amber,red}",
        help=f"for a CI gate: after the audit, exit with status {FAIL_ON_STATUS} and the "
        "verdict line on stderr when the verdict is this light or worse (amber: amber or red; "
        "red: red only)",
    )
    audit.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        help="show Snakemake's whole output live (it always goes to "
        "logs/audit/<name>/stereovar-audit-<time>.log)",
    )
    audit.set_defaults(func=_cmd_audit)
    export = subparsers.add_parser(
        "export",
        help="export renders, variance fields and disparity as EXR, PFM, NPY or PNG files",
        description="Write every scene's renders, variance fields, disparity and glass mask "
        "to results/export/<renderer>/<estimator>/<format>/<scene>/ (the workflow's export "
        "target), with an audit.yaml that audits the export.",
    )
    export.add_argument("--format", required=True, choices=["exr", "pfm", "npy", "png"])
    export.add_argument("--configfile", action="append", help="workflow config(s) to export")
    export.add_argument("-j", "--cores", type=int, default=2, help="cores (default 2)")
    export.set_defaults(func=_cmd_export)
