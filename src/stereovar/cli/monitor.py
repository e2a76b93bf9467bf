"""How ``stereovar audit`` follows a Snakemake run: :class:`_AuditMonitor` reads Snakemake's
printed output and reports one line per stage (:data:`AUDIT_STAGES`) and the failed jobs'
one-line errors."""

from __future__ import annotations

import re
import sys

from .. import errors as error_classes
from .snakemake import PROG

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

        from ..preflight import STATE_DIR, forget_run, record_run

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

        from ..preflight import STATE_DIR, lock_message

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
