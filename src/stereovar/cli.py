"""Command-line interface: ``stereovar <group> <command> ...``.

Commands are grouped with argparse subparsers. To add a group (e.g. ``stereovar backend``),
write a ``_register_<group>(subparsers)`` function that adds its parser and sets
``func=<handler>`` on each leaf command, and call it from :func:`build_parser`. Handlers take
the parsed namespace and return an exit status. Heavy modules (numpy, mitsuba, ...) are
imported inside the handlers so that ``stereovar --help`` stays fast.

Every :class:`~stereovar.errors.StereovarError` is printed as one line,
``stereovar: error: <message>``, on stderr and the exit status is 2.
"""

from __future__ import annotations

import argparse
import contextvars
import re
import sys

from . import errors as error_classes
from .errors import StereovarError

PROG = "stereovar"


# --------------------------------------------------------------------------------------------
# stereovar scenes ...
# --------------------------------------------------------------------------------------------


def _cmd_scenes_generate(args: argparse.Namespace) -> int:
    from .scenes.generate import write_scenes

    if args.count < 1:
        raise StereovarError(f"--count must be >= 1, got {args.count}")
    if args.seed < 0:
        raise StereovarError(f"--seed must be >= 0, got {args.seed}")
    paths = write_scenes(args.out, args.count, args.seed)
    for path in paths:
        print(path)
    return 0


def _cmd_scenes_validate(args: argparse.Namespace) -> int:
    from .scenes.spec import load_scene_spec, scene_spec_digest

    for file in args.files:
        spec = load_scene_spec(file)
        print(f"{file}: ok ({scene_spec_digest(spec)[:12]})")
    if args.variant != "none":
        from .renderers import get_renderer

        backend = get_renderer(args.renderer).backend(args.variant)
        print(
            f"back end: {backend['renderer']} {backend['renderer_version']}, "
            f"variant {backend['variant']} (render.variant: {args.variant})"
        )
    return 0


def _register_scenes(subparsers) -> None:
    scenes = subparsers.add_parser(
        "scenes", help="generate and validate scene specs", description="Scene specs."
    )
    sub = scenes.add_subparsers(dest="scenes_command", metavar="COMMAND", required=True)

    gen = sub.add_parser(
        "generate",
        help="write procedurally generated scenes",
        description="Write scene_000.yaml ... to --out; the same --count/--seed always gives "
        "the same files, and scene i does not depend on --count.",
    )
    gen.add_argument("--count", type=int, default=20, help="number of scenes (default 20)")
    gen.add_argument("--seed", type=int, default=0, help="run seed (default 0)")
    gen.add_argument("--out", default="scenes", help="output directory (default scenes)")
    gen.set_defaults(func=_cmd_scenes_generate)

    val = sub.add_parser(
        "validate",
        help="check scene spec files",
        description="Validate scene specs against the schema and cross references (for an "
        "XML scene, the file and every file it reads), then the render back end on this "
        "machine; prints 'FILE: ok (digest)' per file and the back end, or one error line and "
        "exit status 2.",
    )
    val.add_argument("files", nargs="+", metavar="FILE", help="scene spec YAML files")
    val.add_argument(
        "--renderer", default="mitsuba", help="renderer whose back end to check (default mitsuba)"
    )
    val.add_argument(
        "--variant",
        default="auto",
        help="render.variant to resolve on this machine (default auto; 'none' skips the "
        "back-end check)",
    )
    val.set_defaults(func=_cmd_scenes_validate)


# --------------------------------------------------------------------------------------------
# stereovar audit / export
# --------------------------------------------------------------------------------------------


def _project_root():
    """The directory a command works in: the current one. Configs' relative paths, results,
    logs and Snakemake's state are all relative to it, as for ``snakemake``; the workflow
    itself is the installed package's or the checkout's (:func:`_workflow`)."""
    from pathlib import Path

    return Path.cwd()


def _workflow():
    """The folder of the workflow's Snakefile (:func:`stereovar.workflow_home.workflow_root`)."""
    from .workflow_home import workflow_root

    return workflow_root()


def _snakemake(args: list, root) -> int:
    """Run ``snakemake --snakefile <workflow>/Snakefile ARGS`` in ``root``; its output goes to
    the terminal, or, while a command has set :data:`_MONITOR` (``stereovar audit``), through
    that monitor."""
    import subprocess

    snakefile = _workflow() / "Snakefile"
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(snakefile), *args]
    monitor = _MONITOR.get()
    if monitor is not None:
        return monitor.run(cmd, root)
    print("stereovar: running " + " ".join(cmd[1:]), file=sys.stderr)
    return subprocess.run(cmd, cwd=root, check=False).returncode


#: The :class:`_AuditMonitor` that :func:`_snakemake` runs Snakemake through, if any.
_MONITOR: contextvars.ContextVar = contextvars.ContextVar("stereovar_monitor", default=None)

#: The stages ``stereovar audit`` reports, in order, and the workflow rules of each. A rule
#: named nowhere counts as ``statistics``; ``all`` (the target, no work) counts nowhere.
AUDIT_STAGES = {
    "import": ("audit_import",),
    "statistics": (
        "variance",
        "warp",
        "correlation",
        "statistics_table",
        "cross_scene_table",
        "spp_sweep_table",
        "statistics_dot_figure",
        "rho_vs_seeds_figure",
        "audit_teaser",
        "audit_thumbnail",
    ),
    "controls": ("audit_seeding", "estimator_check", "estimator_tables", "estimators"),
    "intervention": ("intervention", "intervention_table", "margin_figure"),
    "mitigations": (
        "render_policy",
        "render_aux",
        "transform",
        "mitigation_scene",
        "mitigations_table",
        "mitigations",
    ),
    "probe": ("probe_train", "probe_test", "probe_table", "probe"),
    "verdict": ("audit_verdict",),
}
_STAGE_OF = {rule: stage for stage, rules in AUDIT_STAGES.items() for rule in rules}

# What the monitor reads in Snakemake's output, the only account of the run Snakemake gives
# without a logger plugin installed: the "Job stats:" table (jobs planned per rule), each job's
# header ("rule X:" or "localrule X:", then "jobid: N"), "Finished jobid: N (Rule: X)"
# (Snakemake 9; "Finished job N." before it), "Error in rule X:" blocks with the job's
# "log:", "Nothing to be done", and the jobs' own log lines ("<date> <time> LEVEL message",
# stereovar.jobs.common.run_job), whose errors are one "error: ..." line.
_STAMP = r"\d{4}-\d\d-\d\d[ T]\d\d:\d\d:\d\d(?:[,.]\d+)?"
_STATS_ROW = re.compile(r"(\S+)\s+(\d+)")
_JOB_HEADER = re.compile(r"(?:local)?(?:rule|checkpoint) (\S+):")
_JOB_ID = re.compile(r"\s+jobid: (\d+)")
_RENDERER = re.compile(r"\s+wildcards: (?:.*, )?renderer=([^,\s]+).*")
_FINISHED = re.compile(r"Finished jobid: (\d+)(?: \(Rule: ([^)\s]+)\))?|Finished job (\d+)\.")
_FAILED = re.compile(r"Error in rule (\S+):")
_FAILED_LOG = re.compile(r"\s+log: (.*?)(?: \(check log file\(s\) for error details\))?")
_JOB_LINE = re.compile(rf"{_STAMP} ([A-Z]+) (.*)")
_EXCEPTION = re.compile(r"(\w*(?:Error|Exception))(?: in (?:rule \S+ in )?(?:file|line) .*)?:")
#: The last line of a Python traceback: ``OSError: [Errno 28] No space left on device``.
_RAISED = re.compile(r"(\w*(?:Error|Exception)): (.+)")
#: Exceptions Snakemake raises to say that a job failed (the job's own error is in its log).
_JOB_FAILED = ("RuleException", "CalledProcessError")
#: The workflow's own one-line errors (``stereovar.errors.exit_with_one_line``), and the
#: lines it prints with the same prefix that are not errors.
_WORKFLOW_LINE = "stereovar: "
_WORKFLOW_NOTES = ("warning:", "removed the lock")


def _job_error(line: str) -> str | None:
    """The message of a job's ``ERROR`` log line (without its ``error:``), else None."""
    match = _JOB_LINE.fullmatch(line.rstrip("\n"))
    if not match or match.group(1) != "ERROR":
        return None
    message = match.group(2).strip()
    return message[len("error:") :].strip() if message.startswith("error:") else message


def _log_error(path) -> str | None:
    """The first error line of a job's log file, else its last line; None without one."""
    from pathlib import Path

    try:
        lines = Path(path).read_text(errors="replace").splitlines()
    except OSError:
        return None
    errors = [m for m in map(_job_error, lines) if m]
    last = [line.strip() for line in lines if line.strip()]
    return errors[0] if errors else (last[-1] if last else None)


class _AuditMonitor:
    """Snakemake's run of an audit: its whole output goes to ``log`` (and, ``verbose``, live
    to stderr); the monitor follows it and prints one line per stage on stderr (``import:
    ... done``), and after the run the failed jobs' one-line errors (:meth:`errors`).

    Stages advance in :data:`AUDIT_STAGES` order: a stage is done when every job the
    "Job stats:" table planned for its rules has finished and the stages before it are done.
    A job on a mitigated copy of the audit's renders (wildcard ``renderer``
    ``<source>/<mitigation>``: its variance, warp, correlation, intervention) counts as
    ``mitigations``, from the moment it starts (until then, as its rule's stage).
    """

    def __init__(
        self,
        log,
        *,
        import_label: str,
        source: str = "",
        verbose: bool = False,
        command: str = "",
    ):
        from collections import Counter, deque

        self.log, self.import_label, self.verbose = log, import_label, verbose
        self.command = command  # the stereovar command line, for the run's record
        self.root = None  # the folder Snakemake runs in
        self.configfiles: list = []  # its --configfile options
        self.log_error = None  # why the log stopped being written, if it did
        self.planned: dict = {}  # stage: jobs
        self.finished: Counter = Counter()  # stage: jobs
        self.rule_of: dict = {}  # job id: rule
        self.stage_of: dict = {}  # job id: stage, for jobs not in their rule's
        self.source = source  # the audit's renderer wildcard, audit/<name>
        self.failed: list = []  # {"rule", "logs"} per "Error in rule" block
        self.job_errors: list = []  # the jobs' ERROR lines in the output
        self.tail: deque = deque(maxlen=500)
        self.stats = None  # None, "reading", "read"
        self.nothing = False  # "Nothing to be done"
        self.total = None  # jobs planned, all rules
        self.shown: list = []  # stages whose line is complete
        self.open = None  # the stage whose line is printed, not yet ended
        self._rule = None
        self._job = None
        self._block = None

    # -- running ------------------------------------------------------------------------------

    def run(self, cmd: list, root) -> int:
        """Run ``cmd`` in ``root``, following its output (:meth:`feed`); the Snakemake
        process is recorded in ``root/.snakemake`` while it runs
        (:func:`stereovar.preflight.record_run`), so that another run it locks out can
        say which process holds the lock. Returns its exit status."""
        import os
        import subprocess
        from pathlib import Path

        from .preflight import STATE_DIR, forget_run, record_run

        self.root = Path(root)
        self.configfiles = [cmd[k + 1] for k, arg in enumerate(cmd[:-1]) if arg == "--configfile"]
        header = "stereovar: running " + " ".join(cmd[1:]) + "\n"
        self._log(header)
        if self.verbose:
            sys.stderr.write(header)
        env = {**os.environ, "PYTHONUNBUFFERED": "1", "PYTHONIOENCODING": "utf-8"}
        proc = subprocess.Popen(
            cmd,
            cwd=root,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            encoding="utf-8",
            errors="replace",
            bufsize=1,
        )
        try:
            record = record_run(self.root / STATE_DIR, proc.pid, self.command)
        except OSError:  # the record only names the process: the run goes on without it
            record = None
        try:
            for line in proc.stdout:
                self._log(line)
                if self.verbose:
                    sys.stderr.write(line)
                    sys.stderr.flush()
                self.feed(line)
        except KeyboardInterrupt:  # Snakemake got it too: let it stop, keep what it says
            for line in proc.stdout:
                self._log(line)
        finally:
            proc.stdout.close()
            rc = proc.wait()
            if record is not None:
                forget_run(record)
        return rc

    def _log(self, text: str) -> None:
        """Write to the log file; once that fails (a full disk), the run goes on and
        :attr:`log_error` says why the log ends early."""
        if self.log_error is not None:
            return
        try:
            self.log.write(text)
            self.log.flush()
        except OSError as err:
            self.log_error = err.strerror or str(err)

    def feed(self, line: str) -> None:
        """Follow one line of Snakemake's output."""
        line = line.rstrip("\n")
        self.tail.append(line)
        if self.stats == "reading":
            row = _STATS_ROW.fullmatch(line.strip())
            if row and row.group(1) == "total" or not line.strip():
                self.stats = "read"
                self.total = int(row.group(2)) if row else None
                self._planned()
            elif row and row.group(1) != "job":
                stage = self._stage(row.group(1))
                if stage:
                    self.planned[stage] = self.planned.get(stage, 0) + int(row.group(2))
            return
        if self._block is not None:
            if line[:1].isspace():
                logs = _FAILED_LOG.fullmatch(line)
                if logs:
                    self._block["logs"] += [p for p in logs.group(1).split(", ") if p]
                return
            self._block = None
        message = _job_error(line)
        if message:
            if message not in self.job_errors:
                self.job_errors.append(message)
        elif line == "Job stats:" and self.stats is None:
            self.stats = "reading"
        elif line.startswith("Nothing to be done"):
            self.nothing = True
        elif match := _JOB_HEADER.fullmatch(line):
            self._rule, self._job = match.group(1), None
        elif (match := _JOB_ID.fullmatch(line)) and self._rule:
            self._job = match.group(1)
            self.rule_of[self._job] = self._rule
        elif (match := _RENDERER.fullmatch(line)) and self._job:
            self._mitigated(self._job, match.group(1))
        elif match := _FINISHED.match(line):
            jobid = match.group(1) or match.group(3)
            stage = self.stage_of.get(jobid) or self._stage(
                match.group(2) or self.rule_of.get(jobid)
            )
            if stage:
                self.finished[stage] += 1
                if self.stats:
                    self.planned[stage] = max(self.planned.get(stage, 0), self.finished[stage])
                    self._advance()
        elif match := _FAILED.fullmatch(line):
            self._block = {"rule": match.group(1), "logs": []}
            self.failed.append(self._block)

    def _mitigated(self, jobid: str, renderer: str) -> None:
        """A job on a mitigated copy of the renders counts as ``mitigations``."""
        stage = self._stage(self.rule_of[jobid])
        if (
            not self.source
            or not renderer.startswith(self.source + "/")
            or stage in (None, "mitigations")
        ):
            return
        self.stage_of[jobid] = "mitigations"
        if self.stats:
            self.planned[stage] = self.planned.get(stage, 1) - 1
            self.planned["mitigations"] = self.planned.get("mitigations", 0) + 1
            self._advance()

    @staticmethod
    def _stage(rule):
        if not rule or rule == "all":
            return None
        return _STAGE_OF.get(rule, "statistics")

    # -- progress lines -----------------------------------------------------------------------

    def _label(self, stage: str) -> str:
        if stage == "import":
            return self.import_label
        return stage

    def _print(self, text: str, end: str = "\n") -> None:
        if not self.verbose:
            print(text, end=end, file=sys.stderr, flush=True)

    def _begin(self, stage: str) -> None:
        self.open = stage
        self._print(f"{self._label(stage)} ... ", end="")

    def _end(self, word: str) -> None:
        self._print(word)
        self.shown.append(self.open)
        self.open = None

    def _planned(self) -> None:
        """The table is read: an audit whose import is up to date says so first."""
        if not self.planned.get("import"):
            self._print(f"{self.import_label} ... up to date")
            self.shown.append("import")
        self._advance()

    def _advance(self, final: bool = False) -> None:
        for stage in AUDIT_STAGES:
            if stage in self.shown or not self.planned.get(stage):
                continue
            if self.open != stage:
                self._begin(stage)
            if not final and self.finished[stage] < self.planned[stage]:
                return
            n = self.finished[stage]
            self._end(
                "done" if stage in ("import", "verdict") else f"done ({n} job{'s' * (n != 1)})"
            )

    def finish(self, rc: int) -> None:
        """End the progress lines after Snakemake exited with ``rc``."""
        if rc == 0:
            if self.nothing and not self.stats:
                self._print(f"{self.import_label} ... up to date")
            if self.nothing or self.total == 0:  # --until prints a table of no jobs
                self._print("Nothing to be done: every result is up to date")
                return
            if not self.stats:  # no table read: report what finished
                self.planned = dict(self.finished)
            self._advance(final=True)
            return
        failed = {self._stage(job["rule"]) for job in self.failed}
        if self.open:
            self._end("failed" if self.open in failed else "stopped")
        for stage in AUDIT_STAGES:
            if stage in failed and stage not in self.shown:  # failed before its line began
                self._begin(stage)
                self._end("failed")

    # -- errors -------------------------------------------------------------------------------

    def job_logs(self) -> list:
        """The log files of the jobs that failed."""
        return list(dict.fromkeys(p for job in self.failed for p in job["logs"]))

    def errors(self, rc: int) -> list:
        """One line per distinct error of a failed run: each failed job's error line (from
        its log file, else from the output); else, for a run stopped before its jobs, who
        holds the lock that stopped it (:func:`stereovar.preflight.lock_message`), the
        workflow's own ``stereovar:`` line, or the exception Snakemake stopped with (a full
        disk said as such); else its exit status."""
        messages = []
        for job in self.failed:
            message = next(filter(None, map(_log_error, job["logs"])), None)
            messages.append(message or f"rule {job['rule']} failed")
        if self.failed and not any(map(_log_error, self.job_logs())):
            messages = self.job_errors or messages
        if not messages:
            messages = [
                self._locked()
                or self._workflow_error()
                or self._exception()
                or f"snakemake stopped with exit status {rc}"
            ]
        return list(dict.fromkeys(messages))

    def _locked(self) -> str | None:
        """Who holds the lock, when Snakemake stopped because the folder is locked."""
        if self.root is None or not any(line.startswith("LockException") for line in self.tail):
            return None
        import shlex

        from .preflight import STATE_DIR, lock_message

        configs = [arg for f in self.configfiles for arg in ("--configfile", f)]
        unlock = shlex.join([PROG, "run", *configs, "--", "--unlock"])
        return lock_message(self.root / STATE_DIR, unlock)

    def _workflow_error(self) -> str | None:
        """The workflow's last ``stereovar: <message>`` line (it stopped with it), without
        the prefix; lines with that prefix that are not errors are passed over."""
        for line in reversed(self.tail):
            if line.startswith(_WORKFLOW_LINE):
                message = line[len(_WORKFLOW_LINE) :].strip()
                if message and not message.startswith(_WORKFLOW_NOTES):
                    return message
        return None

    def _exception(self) -> str | None:
        lines = list(self.tail)
        for k, line in enumerate(lines):
            match = _EXCEPTION.fullmatch(line.strip())
            if not match or match.group(1) in _JOB_FAILED:
                continue
            rest = [text.strip() for text in lines[k + 1 :] if text.strip()]
            if rest and "did not complete successfully" not in rest[0]:
                ours = isinstance(getattr(error_classes, match.group(1), None), type)
                return rest[0] if ours else f"{match.group(1)}: {rest[0]}"
        raised = [m for m in map(_RAISED.fullmatch, map(str.strip, lines)) if m]
        if not raised:
            return None
        kind, message = raised[-1].groups()
        if "[Errno 28]" in message:  # ENOSPC: Snakemake's lock or records, or a job's output
            import shutil

            where = self.root or "."
            free = shutil.disk_usage(where).free / 10**6
            return (
                f"the disk of {where} is full ({free:.1f} MB free; Snakemake stopped with "
                f"{kind}: {message}); free space on it, then run the same command again"
            )
        return f"{kind}: {message}"


def _audit_log(root, name: str):
    """A new file for the whole Snakemake output of one ``stereovar audit``,
    ``logs/audit/<name>/stereovar-audit-<time>.log`` under ``root`` (never one that exists)."""
    import time

    folder = root / "logs" / "audit" / name
    stem = f"stereovar-audit-{time.strftime('%Y%m%d-%H%M%S')}"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        for k in range(1, 1000):
            path = folder / f"{stem}{'' if k == 1 else f'-{k}'}.log"
            try:
                return path, open(path, "x", encoding="utf-8")  # noqa: SIM115 (caller closes)
            except FileExistsError:
                continue
    except OSError as err:
        raise StereovarError(
            f"{folder}: cannot create the run's log file there ({err.strerror or err}); "
            "make room or make it writable, then run the same command again"
        ) from None
    raise StereovarError(f"{folder}: cannot create a new log file there")


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
            match = _JOB_LINE.fullmatch(line)
            text = (match.group(2) if match else line).strip()
            if text.startswith("warning:"):
                text = text[len("warning:") :].strip()
                if text not in warnings:
                    warnings.append(text)
    return warnings


def _workflow_config(root, files) -> dict:
    """The config the workflow would run with: ``config.yaml`` of ``root`` (else the
    workflow's own, as the Snakefile reads it), then ``files``
    (as ``--configfile``), validated against the workflow's schema with its defaults filled
    in (:func:`stereovar.config.load_config`); one line for anything it refuses."""
    from .config import load_config

    workflow = _workflow()
    first = root / "config.yaml" if (root / "config.yaml").is_file() else workflow / "config.yaml"
    return load_config([first, *files], workflow / "workflow" / "schemas" / "config.schema.yaml")


def _audit_preflight(root, config: dict, discovery) -> None:
    """The workflow's checks of an audit, made before Snakemake starts and before anything
    is written: the folders the run writes can be written, the disk has room for
    Snakemake's lock (:mod:`stereovar.preflight`), and the run config's mitigations and
    memory (:func:`stereovar.audit.run.check_audit_run`); one line for the first problem."""
    from .audit.run import audit_run_config, check_audit_run
    from .preflight import WRITTEN_FOLDERS, check_free_space, check_writable

    check_writable([root / d for d in WRITTEN_FOLDERS])
    check_free_space(root)
    check_audit_run({**config, **audit_run_config(config, discovery)}, discovery)


def _cmd_audit(args: argparse.Namespace) -> int:
    import json
    import os
    from pathlib import Path

    from .audit.run import PREVIOUS, audit_paths, discover_audit
    from .layout import audit_source
    from .schema import load_yaml

    root = _project_root()
    config = Path(args.config)
    if not config.is_file():
        raise StereovarError(f"{config}: no such config file; give the audit's YAML config")
    data = load_yaml(config, "audit config", error=StereovarError) or {}
    settings = data.get("audit") if isinstance(data, dict) else None
    if not isinstance(settings, dict):
        raise StereovarError(
            f"{config}: no audit: section; add one (keys: name, renders, views, disparity, "
            "convention; see the documentation's Auditing your renders page, docs/audit.md)"
        )
    # The whole config, as the workflow will see it, before any file is read; then the
    # files, found (not read) as the workflow finds them; the import is the workflow's (one
    # audit_import job per frame).
    workflow_config = _workflow_config(root, [config])
    settings = workflow_config["audit"]
    name = settings["name"]
    discovery = discover_audit(settings)
    _audit_preflight(root, workflow_config, discovery)
    command = ["-j", str(args.cores), "all", "--configfile", str(config.resolve())]
    if args.import_only:
        command += ["--until", "audit_import"]
    log_path, log = _audit_log(root, name)
    shown_log = os.path.relpath(log_path)
    monitor = _AuditMonitor(
        log,
        import_label=f"import: {discovery.summary()}",
        source=audit_source(name),
        verbose=args.verbose,
        command=f"{PROG} audit {args.config}",
    )
    token = _MONITOR.set(monitor)
    try:
        rc = _snakemake(command, root)
    finally:
        _MONITOR.reset(token)
        try:
            log.close()
        except OSError as err:  # a full disk: the end of the log is lost, not the run
            monitor.log_error = monitor.log_error or err.strerror or str(err)
    monitor.finish(rc)
    paths = audit_paths(name)
    summary = root / paths["summary"]
    lines = json.loads(summary.read_text())["summary"] if rc == 0 and not args.import_only else []
    # the import's warnings, each once: those the verdict's summary does not already say
    for warning in _import_warnings(root, name, [f.name for f in discovery.frames]):
        if not any(warning in line for line in lines):
            print(f"warning: {warning}", file=sys.stderr)
    if monitor.log_error:
        print(f"warning: the log ends early: {monitor.log_error}", file=sys.stderr)
    if rc != 0:
        for message in monitor.errors(rc):
            print(f"{PROG}: error: {' '.join(message.split())}", file=sys.stderr)
        previous = root / Path(paths["verdict_html"]).parent / PREVIOUS
        if not (root / paths["verdict_html"]).exists() and (previous / "verdict.html").exists():
            print(
                f"the verdict before this run, set aside as out of date: {previous}/",
                file=sys.stderr,
            )
        jobs = monitor.job_logs()
        print(
            f"log: {shown_log}" + (f" (the failed job's: {', '.join(jobs)})" if jobs else ""),
            file=sys.stderr,
        )
        return rc
    if args.import_only:
        records = root / Path(paths["summary"]).parent / "import"
        print(f"imported {name}: one record per frame in {records}")
    else:
        print("\n".join(lines))
        print(f"verdict page: {summary.parent / 'verdict.html'}")
    print(f"log: {shown_log}")
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .audit.export import check_export_targets, export_targets

    root = _project_root()
    files = [Path(f) for f in args.configfile or []]
    config = _workflow_config(root, files)
    targets = export_targets(config, args.format)
    check_export_targets(targets)  # a link or a stray folder would pass for an export
    options = ["-j", str(args.cores), "export", "--config", f"export={{formats: [{args.format}]}}"]
    for f in args.configfile or []:
        options[3:3] = ["--configfile", f]
    rc = _snakemake(options, root)
    if rc != 0:
        return rc
    check_export_targets(targets)
    folder = Path(targets[0]).parent
    scenes = ", ".join(Path(t).name for t in targets)
    print(
        f"exported {len(targets)} scene{'s' * (len(targets) != 1)} to {folder}/ ({scenes}); "
        "each scene directory has an audit.yaml that audits it"
    )
    return 0


def _register_audit(subparsers) -> None:
    audit = subparsers.add_parser(
        "audit",
        help="audit renders made elsewhere for the cross-view variance cue",
        description="Import N >= 2 renders per view of stereo frames and their ground truth "
        "(the audit: section of CONFIG), run every statistic, control and the intervention on "
        "them, and print the verdict's summary; the page is results/audit/<name>/verdict.html. "
        "Prints one line per stage (import, statistics, controls, intervention, mitigations, "
        "verdict) and the import's warnings; Snakemake's whole output goes to a log file whose "
        "path is printed (-v shows it live). A failed job: its one-line error, the log's "
        "path and a non-zero exit status.",
    )
    audit.add_argument("config", metavar="CONFIG", help="YAML config with an audit: section")
    audit.add_argument("-j", "--cores", type=int, default=2, help="cores (default 2)")
    audit.add_argument(
        "--import-only",
        action="store_true",
        help="run only the import jobs (one per frame: decode, check, sign-check, store)",
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


# --------------------------------------------------------------------------------------------
# stereovar probe
# --------------------------------------------------------------------------------------------


def _cmd_probe(args: argparse.Namespace) -> int:
    """The user's own network on the counterfactual inputs of the audit's frames (a config
    with an audit: section) or of the run's scenes; their stores are made first if missing
    (workflow rule ``probe_model_frames``)."""
    from pathlib import Path

    if args.cores < 1:
        raise StereovarError(f"-j must be >= 1, got {args.cores}")
    for option, value in (("--test-frames", args.test_frames), ("--batch", args.batch)):
        if value < 1:
            raise StereovarError(f"{option} must be >= 1, got {value}")
    weights = Path(args.weights)
    if not weights.is_file():
        raise StereovarError(
            f"weights file {weights} does not exist; give the model's saved weights"
        )
    files = []
    if args.config:
        if not Path(args.config).is_file():
            raise StereovarError(f"{args.config}: no such config file; give an existing --config")
        files.append(args.config)
    from .jobs.probe_model import frames_manifest, probe_model_job, read_manifest
    from .layout import audit_source, probe_model_tables
    from .probe.user_model import load_user_model

    model = load_user_model(args.model, weights, device=args.device)  # its errors first
    root = _project_root()
    config = _workflow_config(root, files)
    audit = config.get("audit")
    source = audit_source(audit["name"]) if audit else config["render"]["renderer"]
    manifest = frames_manifest(source)
    options = ["-j", str(args.cores), manifest, "--forcerun", "probe_model_frames"]
    if files:
        options += ["--configfile", *[str(Path(f).resolve()) for f in files]]
    rc = _snakemake(options, root)
    if rc != 0:
        raise StereovarError(
            f"the frames' stores could not be made (snakemake exit status {rc}); see its "
            "output above"
        )
    scenes, stores = read_manifest(root / manifest)
    paths = probe_model_tables(source)
    outputs = dict(zip(("csv", "md", "tex", "html"), paths, strict=True))
    settings = {"test_frames": args.test_frames, "batch": args.batch, "seed": args.seed}
    record = probe_model_job(
        stores, outputs, scenes=scenes, factory=args.model, weights=weights,
        device=args.device, settings=settings, source=source, model=model,
    )
    print(record["reading"])
    print(f"table: {paths[1]}")
    return 0


def _register_probe(subparsers) -> None:
    probe = subparsers.add_parser(
        "probe",
        help="does your own stereo network use the Monte Carlo cue?",
        description="Run your PyTorch stereo network on the counterfactual inputs of the "
        "audit's frames (CONFIG with an audit: section) or of the run's scenes (their renders "
        "are made if missing): its accuracy and EPE drop when the right view's Monte Carlo "
        "residual is shuffled, against the drop under the same shuffle of camera-law noise, "
        "with intervals, and a one-line reading. The model maps (left, right) sRGB images "
        "(B, 3, H, W) in [0, 1] to disparity (B, 1, H, W) or (B, H, W), right pixel at x - d "
        "(docs: Probing your own network).",
    )
    probe.add_argument(
        "--model", required=True, metavar="MODULE:FACTORY",
        help="package.module:factory (or path/to/file.py:factory) building the model",
    )
    probe.add_argument(
        "--weights", required=True, metavar="FILE",
        help="its state_dict (or a dict with state_dict), read with torch.load(weights_only=True)",
    )
    probe.add_argument(
        "--config", metavar="CONFIG",
        help="workflow config; with an audit: section, the audit's frames (default: "
        "config.yaml here, the run's scenes)",
    )
    probe.add_argument("--device", default="cpu", help="torch device (default cpu)")
    probe.add_argument(
        "--test-frames", type=int, default=4, help="renders per frame tested (default 4)"
    )
    probe.add_argument("--batch", type=int, default=4, help="pairs per forward pass (default 4)")
    probe.add_argument("--seed", type=int, default=0, help="shuffles' and bootstrap's seed")
    probe.add_argument("-j", "--cores", type=int, default=2, help="cores (default 2)")
    probe.set_defaults(func=_cmd_probe)


# --------------------------------------------------------------------------------------------
# stereovar init / run / report
# --------------------------------------------------------------------------------------------

#: The starter audit config ``stereovar init`` writes; ``{name}``, ``{renders}``, ``{views}``,
#: ``{disparity}`` and ``{convention}`` are filled in (placeholders, or the example's files).
AUDIT_STARTER = """\
# stereovar audit audit.yaml: audit renders made elsewhere for the cross-view variance cue.
# Keys, types and defaults: the documentation's configuration reference (audit: section).
audit:
  # results/audit/<name>/verdict.html
  name: {name}
  renders: {renders}
  # the {{view}} values in the paths
  views: {views}
  # the left view's disparity (add {{view}} to give both views')
  disparity: {disparity}
  # conventional: x_R = x_L - d (Middlebury, KITTI, SceneFlow); paper: x_R = x_L + d
  convention: {convention}
  # glass_mask: masks/{{frame}}.png      # or segmentation: seg/{{frame}}.png, glass_ids: [3]
  # depth: depth/{{frame}}.exr           # instead of disparity, with focal_px and baseline_m
  # transfer: srgb                     # PNG renders: srgb (default, with a warning) or linear
  # spp: 128                           # for the tables; null = not given (0)
  # mitigations: [denoise]             # test mitigations on these renders
  # probe: true                        # train and test the learned matcher on these frames
"""


def _write_new(path, text: str) -> bool:
    """Write ``text`` to ``path`` atomically unless it exists; True if written."""
    from .io.store import atomic_path

    if path.exists():
        print(f"kept {path} (it exists)")
        return False
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    print(f"wrote {path}")
    return True


def _cmd_init(args: argparse.Namespace) -> int:
    import os

    root = _project_root()
    fields = {
        "name": "my_renders",
        "renders": "renders/{frame}/{view}/seed_{seed}.exr",
        "views": "{left: L, right: R}",
        "disparity": "disparity/{frame}.pfm",
        "convention": "conventional",
    }
    if args.example:
        from .audit.synthetic import write_synthetic_audit

        folder = root / "data" / "synthetic"
        for path in (folder, root / "audit.yaml"):
            if path.exists():
                raise StereovarError(
                    f"{path} exists; remove it or run stereovar init --example in another "
                    "directory"
                )
        settings, _ = write_synthetic_audit(os.path.relpath(folder, root))
        fields = {**settings, "views": "{left: L, right: R}"}
        print(f"wrote {folder}: 2 synthetic frames with a known cross-view correlation")
    _write_new(root / "config.yaml", (_workflow() / "config.yaml").read_text())
    _write_new(root / "audit.yaml", AUDIT_STARTER.format(**fields))
    print("next: stereovar run -j2 (the default experiment) or stereovar audit audit.yaml")
    return 0


def _configfiles(args) -> list:
    """``--preset`` configs (the workflow's) then ``--configfile`` configs, as given."""
    from pathlib import Path

    from .workflow_home import preset_path

    files = [str(preset_path(name)) for name in args.preset or []]
    for f in args.configfile or []:
        if not Path(f).is_file():
            raise StereovarError(f"{f}: no such config file; give an existing --configfile")
        files.append(f)
    return files


def _cmd_run(args: argparse.Namespace) -> int:
    if args.cores < 1:
        raise StereovarError(f"-j must be >= 1, got {args.cores}")
    files = _configfiles(args)
    options = ["-j", str(args.cores), *(args.targets or ["all"])]
    if files:
        options += ["--configfile", *files]
    return _snakemake([*options, *args.snakemake_args], _project_root())


def _cmd_report(args: argparse.Namespace) -> int:
    files = _configfiles(args)
    options = ["--report", args.output]
    if files:
        options += ["--configfile", *files]
    rc = _snakemake([*options, *args.snakemake_args], _project_root())
    if rc == 0:
        print(f"report: {args.output}")
    return rc


def _add_configs(parser) -> None:
    parser.add_argument(
        "--configfile", action="append", metavar="FILE", help="config merged on top (repeatable)"
    )
    parser.add_argument(
        "--preset",
        action="append",
        metavar="NAME",
        help="the workflow's preset NAME (workflow/presets/NAME.yaml: paper, paper-moments, "
        "probe), merged before --configfile",
    )


def _register_workflow(subparsers) -> None:
    init = subparsers.add_parser(
        "init",
        help="write a starter config.yaml and audit.yaml here",
        description="Write config.yaml (the workflow's defaults, commented) and audit.yaml (an "
        "audit config to fill in) in the current directory; an existing file is kept.",
    )
    init.add_argument(
        "--example",
        action="store_true",
        help="also write two synthetic frames under data/synthetic and point audit.yaml at them",
    )
    init.set_defaults(func=_cmd_init)
    run = subparsers.add_parser(
        "run",
        help="run the workflow here (results under ./results)",
        description="Run the stereovar workflow with the current directory as its working "
        "directory: config.yaml here if there is one (else the defaults), then --preset and "
        "--configfile configs. Options after -- go to snakemake unchanged.",
    )
    run.add_argument("targets", nargs="*", metavar="TARGET", help="targets (default: all)")
    run.add_argument("-j", "--cores", type=int, default=2, help="cores (default 2)")
    _add_configs(run)
    run.set_defaults(func=_cmd_run, passthrough=True)
    report = subparsers.add_parser(
        "report",
        help="write Snakemake's report of the run here",
        description="Write Snakemake's self-contained report of the results here (the "
        "workflow's captions, figures and tables). Options after -- go to snakemake.",
    )
    report.add_argument(
        "-o", "--output", default="results/report.html", help="default results/report.html"
    )
    _add_configs(report)
    report.set_defaults(func=_cmd_report, passthrough=True)


# --------------------------------------------------------------------------------------------
# entry point
# --------------------------------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with one subparser per command group."""
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Cross-view Monte Carlo variance correlation in path-traced stereo.",
        formatter_class=argparse.RawDescriptionHelpFormatter,  # --version's line unwrapped
    )
    parser.add_argument("--version", action="version", version=_version())
    subparsers = parser.add_subparsers(dest="command", metavar="GROUP", required=True)
    _register_workflow(subparsers)
    _register_scenes(subparsers)
    _register_audit(subparsers)
    _register_probe(subparsers)
    return parser


def _version() -> str:
    """``stereovar <version> (workflow: <folder>)``."""
    from . import __version__

    try:
        return f"{PROG} {__version__} (workflow: {_workflow()})"
    except StereovarError as err:
        return f"{PROG} {__version__} ({err})"


def main(argv=None) -> int:
    """Run the command line; returns (and, as a script, exits with) the exit status.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        0 on success, 2 on a usage error or a :class:`~stereovar.errors.StereovarError`.
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    passthrough = []
    if "--" in argv:  # snakemake's own options, for the commands that run it
        cut = argv.index("--")
        argv, passthrough = argv[:cut], argv[cut + 1 :]
    parser = build_parser()
    args = parser.parse_args(argv)
    if passthrough and not getattr(args, "passthrough", False):
        parser.error(f"options after -- are for run and report only, not {args.command}")
    args.snakemake_args = passthrough
    try:
        return int(args.func(args) or 0)
    except StereovarError as err:
        message = " ".join(str(err).split())
        print(f"{PROG}: error: {message}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into e.g. `head`, which closed early
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())
