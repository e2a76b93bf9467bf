"""Progress of a workflow run, one line per stage, from Snakemake's log events.

``stereovar run`` and ``stereovar audit`` run Snakemake with the logger plugin
``stereovar`` (package :mod:`snakemake_logger_plugin_stereovar`), which hands each of
Snakemake's log events to a :class:`Progress`: the plan (``RUN_INFO``: jobs per rule), each
job as it starts (``JOB_INFO``: its rule), ends (``JOB_FINISHED``) or fails (``JOB_ERROR``:
its log files) and Snakemake's own errors (``ERROR``). A :class:`Progress` only keeps count
and returns the text to show; nothing here writes, and its clock is a parameter, so every
line can be checked from events and their times alone.

A stage is a group of workflow rules (:mod:`stereovar.stages`). Stages are reported in their
order: a stage is done when every job planned for its rules has finished and the stages
before it are done, so each stage's line is written once, as ``<stage> ... done (<n> jobs;
<k> of <N> in all; about <time> left)``; where several stages are done at once, the last of
them says where the run stands. Inside a long stage, a job that ends :data:`TICK_S` after the
last line says where the run stands: ``<stage> ... <j> of <m> jobs · <k> of <N> in all ·
about <time> left`` (:mod:`stereovar.eta`).
"""

from __future__ import annotations

import re
import time
from collections import Counter
from pathlib import Path

from .eta import Pace, status, time_left_text

# ``name as name``: the stage maps, read here by the logger plugin and by the tests.
from .stages import AUDIT_STAGES as AUDIT_STAGES
from .stages import DEFAULT_STAGE as DEFAULT_STAGE
from .stages import RUN_STAGES as RUN_STAGES
from .stages import STAGE_MAPS as STAGE_MAPS
from .stages import TARGET_RULES as TARGET_RULES
from .stages import rule_stage as rule_stage
from .stages import stage_map as stage_map

#: Seconds after the last line at which a job that ends says where the run stands, where the
#: lines are not rewritten in place (a log file, a pipe).
TICK_S = 30.0

#: Audit stages whose line says only ``done`` (the import counts its frames in the line
#: itself), and that say ``up to date`` when nothing of them runs.
PLAIN_STAGES = ("import",)

#: Snakemake's options after which it runs no job and prints what was asked (``stereovar
#: run -- --unlock``): their output is the command's, not a run's.
NO_RUN_OPTIONS = (
    "--unlock",
    "--cleanup-metadata",
    "--cm",
    "--list-rules",
    "--list",
    "-l",
    "--list-target-rules",
    "--lt",
    "--list-changes",
    "--lc",
    "--list-input-changes",
    "--li",
    "--list-params-changes",
    "--lp",
    "--list-code-changes",
    "--list-untracked",
    "--lu",
    "--summary",
    "-S",
    "--detailed-summary",
    "-D",
    "--dag",
    "--rulegraph",
    "--filegraph",
    "--d3dag",
    "--lint",
    "--report",
    "--containerize",
    "--export-cwl",
    "--print-compilation",
    "--archive",
    "--delete-all-output",
    "--delete-temp-output",
    "--cleanup-shadow",
    "--conda-create-envs-only",
    "--conda-cleanup-envs",
    "--version",
    "-v",
    "--help",
    "-h",
)

_STAMP = r"\d{4}-\d\d-\d\d[ T]\d\d:\d\d:\d\d(?:[,.]\d+)?"
#: A job's own log line, ``<date> <time> LEVEL message`` (stereovar.jobs.common.run_job).
JOB_LINE = re.compile(rf"{_STAMP} ([A-Z]+) (.*)")
#: The first line of Snakemake's account of an exception: ``AuditError in file "x", line 4:``.
_EXCEPTION_HEAD = re.compile(r"(\w+)(?: in (?:rule \S+|file .*|line .*)(?: in .*)?)?[:.]")
#: Exceptions Snakemake raises to say that a job failed (the job's own error is in its log).
JOB_FAILED = ("RuleException", "CalledProcessError")
#: Snakemake's last words after jobs failed: said by the jobs' errors already.
_AFTER_JOBS = "did not complete successfully"


def reports_progress(snakemake_args) -> bool:
    """Whether a run with these extra Snakemake options runs (or plans) jobs, so that its
    output is progress; False for options that ask Snakemake for something else.

    Examples
    --------
    >>> reports_progress(["-n", "--forcerun", "render"]), reports_progress(["--unlock"])
    (True, False)
    """
    return not any(arg.split("=", 1)[0] in NO_RUN_OPTIONS for arg in snakemake_args)


def is_dry_run(snakemake_args) -> bool:
    """Whether these Snakemake options ask for a dry run.

    Examples
    --------
    >>> is_dry_run(["-j1", "-n"]), is_dry_run(["--dry-run"]), is_dry_run(["-np"])
    (True, True, True)
    """
    return any(
        arg in ("--dry-run", "--dryrun")
        or (arg.startswith("-") and not arg.startswith("--") and "n" in arg[1:])
        for arg in snakemake_args
    )


def job_error(line: str):
    """The message of a job's ``ERROR`` log line (without its ``error:``), else None.

    Examples
    --------
    >>> job_error("2026-01-01 10:00:00,123 ERROR error: a.exr: cannot read it")
    'a.exr: cannot read it'
    >>> job_error("2026-01-01 10:00:00,123 INFO done in 1.00 s") is None
    True
    """
    match = JOB_LINE.fullmatch(line.rstrip("\n"))
    if not match or match.group(1) != "ERROR":
        return None
    message = match.group(2).strip()
    return message[len("error:") :].strip() if message.startswith("error:") else message


def log_error(path):
    """The first error line of a job's log file (:func:`job_error`), else its last line;
    None without one (or without the file)."""
    try:
        lines = Path(path).read_text(errors="replace").splitlines()
    except OSError:
        return None
    errors = [m for m in map(job_error, lines) if m]
    last = [line.strip() for line in lines if line.strip()]
    return errors[0] if errors else (last[-1] if last else None)


def exception_line(text: str, exception: str = "", ours=()):
    """One line for Snakemake's account of an exception (its ``ERROR`` event): the first
    line of the message after the ``<Name> in file ..., line N:`` head, with the exception's
    name unless it is one of ``ours`` (the workflow's own one-line errors); None when the
    exception only says that jobs failed (their logs say why).

    Examples
    --------
    >>> exception_line('AuditError in file "/wf/common.smk", line 40:\\nf00.exr: gone',
    ...                "AuditError", ours=("AuditError",))
    'f00.exr: gone'
    >>> exception_line("WorkflowError:\\nAt least one job did not complete successfully.")
    >>> exception_line("MissingInputException in rule x:\\nMissing input files: a", "")
    'MissingInputException: Missing input files: a'
    """
    lines = [line.strip() for line in str(text or "").splitlines()]
    head = _EXCEPTION_HEAD.fullmatch(lines[0]) if lines else None
    name = exception or (head.group(1) if head else "")
    if name in JOB_FAILED:
        return None
    rest = [line for line in lines[1 if head else 0 :] if line]
    if not rest:
        return name or None
    if _AFTER_JOBS in rest[0]:
        return None
    return rest[0] if name in ours or not name else f"{name}: {rest[0]}"


def our_exceptions() -> tuple:
    """The names of the workflow's own exceptions (:mod:`stereovar.errors`), whose message
    is said without the name."""
    from . import errors

    return tuple(
        name
        for name, value in vars(errors).items()
        if isinstance(value, type) and issubclass(value, errors.StereovarError)
    )


def _jobs(n: int) -> str:
    return f"{n} job{'s' * (n != 1)}"


class Progress:
    """What a run has planned and done, per stage, and the lines that say so.

    Each event method returns the text to write (possibly ``""``): whole lines, and in the
    one open stage's line its start (``"statistics ... "``) and, later, its end. A job that
    ends :data:`TICK_S` or more after the last line ended ends the open line with where the
    run stands (:meth:`status`) and begins it again. With ``live`` (a terminal) the open
    line is rewritten in place with its status (``import: 3 frames ... frame 2 of 3 · 1 of 5
    in all · about 20 s left``) at every event instead.

    Parameters
    ----------
    stages : dict
        Stage name: rule names, in order (:data:`~stereovar.stages.RUN_STAGES`,
        :data:`~stereovar.stages.AUDIT_STAGES`).
    labels : dict, optional
        What a stage's line calls it (default: its name), e.g. ``{"import": "import: 2
        frames × 2 views × 4 seeds"}``.
    source : str
        An audit's renderer wildcard (``audit/<name>``), as the logger plugin gives it. A job
        counts in its rule's stage whatever its renderer, so that each stage's total is the
        plan's from the start.
    live : bool
        Rewrite the open line with its status (a terminal).
    clock : callable
        The time in seconds, read at each event (default :func:`time.monotonic`).
    tick : float
        Seconds from the last line to a status line (:data:`TICK_S`).
    """

    def __init__(
        self,
        stages: dict,
        *,
        labels=None,
        source: str = "",
        live: bool = False,
        clock=time.monotonic,
        tick: float = TICK_S,
    ):
        self.stages = stages
        self.labels = dict(labels or {})
        self.source = source
        self.live = live
        self.clock = clock
        self.tick = tick
        self.pace = Pace()  # when each job started and ended: the time left
        self.planned: dict = {}  # stage: jobs
        self.rules: dict = {}  # stage: Counter of rules, as planned
        self.finished: Counter = Counter()  # stage: jobs
        self.job_stages: dict = {}  # job id: stage
        self.job_rules: dict = {}  # job id: rule
        self.running: Counter = Counter()  # stage: jobs started and not ended
        self._noted = False  # the open (not live) line says another stage started
        self.failed: list = []  # {"rule", "jobid", "logs"} per failed job
        self.errors: list = []  # {"exception", "message"} per Snakemake error
        self.nothing = False  # Snakemake said there is nothing to be done
        self.seen_plan = False
        self.shown: list = []  # stages whose line is complete
        self.open = None  # the stage whose line is begun, not yet ended
        self._marks = 0  # per-frame marks written in the open (not live) line
        self._line_at = None  # when the last line ended (or the plan came)

    # -- events ---------------------------------------------------------------------------

    def plan(self, stats: dict) -> str:
        """Snakemake's plan (``RUN_INFO``): jobs per rule, and ``total``."""
        planned: dict = {}
        rules: dict = {}
        for rule, count in stats.items():
            stage = rule_stage(rule, self.stages) if rule != "total" else None
            if stage is not None:
                planned[stage] = planned.get(stage, 0) + int(count)
                rules.setdefault(stage, Counter())[rule] += int(count)
        for stage in set(planned) | set(self.finished):
            planned[stage] = max(planned.get(stage, 0), self.finished[stage])
        first = not self.seen_plan
        self.planned, self.rules, self.seen_plan = planned, rules, True
        if self._line_at is None:
            self._line_at = self.clock()
        text = ""
        if first:
            for stage in PLAIN_STAGES[:1]:
                if stage in self.stages and not self.planned.get(stage):
                    text += f"{self.label(stage)} ... up to date\n"
                    self.shown.append(stage)
        return text + self.advance()

    def job(self, jobid, rule: str, wildcards=None) -> str:
        """A job starts (``JOB_INFO``; in a dry run, every planned job); ``wildcards`` (its
        wildcards, as the plugin passes them) do not change the stage it counts in.

        Where it belongs to another stage than the open line's, and no job of that one
        runs (it waits for jobs still to come), the line says what runs: with ``live``, the
        rewritten line names the stages running and their counts; else the open line gets
        ``· <stage> started``, once, so that it never stands alone for work that is not
        going on."""
        self.job_rules[jobid] = rule
        stage = rule_stage(rule, self.stages)
        if stage is None:
            return ""
        self.job_stages[jobid] = stage
        self.running[stage] += 1
        self.pace.start(jobid, rule, self.clock())
        return self._meanwhile(stage)

    def _meanwhile(self, stage: str) -> str:
        """What the open line says when a job of ``stage`` starts (:meth:`job`)."""
        open_ = self.open
        if open_ is None or stage == open_ or self.running[open_] > 0:
            return ""
        if self.live:
            return self._step(open_)
        if self._noted:
            return ""
        self._noted = True
        return f"· {self.label(stage)} started "

    def _stopped(self, jobid, failed: bool = False) -> str | None:
        """The stage of a job that ended (its count of running jobs one less)."""
        self.pace.end(jobid, self.clock(), failed=failed)
        stage = self.job_stages.get(jobid)
        if stage is None:
            stage = rule_stage(self.job_rules.get(jobid), self.stages)
        if stage is not None and self.running[stage] > 0:
            self.running[stage] -= 1
        return stage

    def done(self, jobid) -> str:
        """A job finished (``JOB_FINISHED``): the lines of the stages now done, or (not
        ``live``) the open line's status where :data:`TICK_S` have passed since the last
        line."""
        stage = self._stopped(jobid)
        if stage is None:
            return ""
        self.finished[stage] += 1
        self.planned[stage] = max(self.planned.get(stage, 0), self.finished[stage])
        text = self.advance()
        due = self._line_at is not None and self.clock() - self._line_at >= self.tick
        if not self.live and self.open is not None and "\n" not in text and due:
            self._line_at = self.clock()
            text += f"{self.status()}\n{self.label(self.open)} ... "
        return text

    def fail(self, rule: str, jobid=None, logs=()) -> None:
        """A job failed (``JOB_ERROR``), its log files ``logs``."""
        self._stopped(jobid, failed=True)
        self.failed.append({"rule": rule, "jobid": jobid, "logs": [str(p) for p in logs]})

    def error(self, message: str, exception: str = "") -> None:
        """Snakemake stopped with an exception (``ERROR``)."""
        self.errors.append({"exception": exception or "", "message": str(message or "")})

    # -- where the run stands -------------------------------------------------------------

    def label(self, stage: str) -> str:
        """What ``stage``'s line calls it."""
        return self.labels.get(stage, stage)

    def totals(self) -> tuple:
        """Jobs finished and planned, all stages."""
        return sum(self.finished.values()), sum(self.planned.values())

    def time_left(self) -> float | None:
        """Seconds the run has left now (:meth:`stereovar.eta.Pace.left`); None before a job
        has finished."""
        planned = Counter()
        for rules in self.rules.values():
            planned.update(rules)
        return self.pace.left(planned, self.clock())

    def status(self, stage=None) -> str:
        """Where the run stands, said in ``stage``'s line (default: the open one): its jobs
        done of its total, the run's, the time left and the other stages running
        (:func:`stereovar.eta.status`)."""
        stage = stage or self.open
        done, total = self.totals()
        left = self.time_left() if done < total else None
        return status(self._count(stage), done, total, left, self._elsewhere())

    def _word(self, stage: str, last: bool) -> str:
        """How a done stage's line ends; the ``last`` of the stages done at once says where
        the run stands."""
        if stage in PLAIN_STAGES:
            return "done"
        parts = [_jobs(self.finished[stage])]
        if last:
            done, total = self.totals()
            parts.append(f"{done} of {total} in all")
            if done < total:
                parts.append(time_left_text(self.time_left()))
        return f"done ({'; '.join(part for part in parts if part)})"

    def _count(self, stage: str) -> str:
        """A stage's count: ``frame k of n`` for the import, else ``k of n jobs``."""
        k, n = self.finished[stage], self.planned.get(stage, 0)
        if stage == "import":
            return f"frame {min(k + 1, n)} of {n}" if k < n else f"{n} of {n} frames"
        return f"{k} of {_jobs(n)}"

    def _elsewhere(self) -> str:
        """The other stages than the open one with jobs running: ``running: calibration 3
        of 8 jobs``."""
        busy = [s for s in self.stages if s != self.open and self.running[s] > 0]
        if not busy:
            return ""
        counts = ", ".join(f"{s} {self.finished[s]} of {_jobs(self.planned.get(s, 0))}"
                           for s in busy)
        return f"running: {counts}"

    # -- lines ----------------------------------------------------------------------------

    def _begin(self, stage: str) -> str:
        self.open, self._marks, self._noted = stage, 0, False
        if self.live:
            return f"\r\x1b[K{self.label(stage)} ... {self.status(stage)}"
        return f"{self.label(stage)} ... "

    def _end(self, word: str) -> str:
        stage, self.open = self.open, None
        self.shown.append(stage)
        self._line_at = self.clock()
        if self.live:
            return f"\r\x1b[K{self.label(stage)} ... {word}\n"
        return f"{word}\n"

    def _step(self, stage: str) -> str:
        """The open line, one more job of it finished and more to come."""
        if self.live:
            return f"\r\x1b[K{self.label(stage)} ... {self.status(stage)}"
        k, n = self.finished[stage], self.planned.get(stage, 0)
        if stage != "import" or n < 2 or k > n or k * 20 // n <= self._marks:
            return ""
        self._marks = k * 20 // n  # at most 20 marks per line
        return f"{k}/{n} "

    def advance(self, final: bool = False) -> str:
        """Lines for the stages that are now done, and the start of the next; ``final``:
        every stage with jobs is done."""
        closing, next_open = [], None
        for stage in self.stages:
            if stage in self.shown or not self.planned.get(stage):
                continue
            if not final and self.finished[stage] < self.planned[stage]:
                next_open = stage
                break
            closing.append(stage)
        text = ""
        for k, stage in enumerate(closing):
            if self.open != stage:
                text += self._begin(stage)
            elif not self.live:
                text += self._step(stage)  # the last frame's mark
            text += self._end(self._word(stage, last=k == len(closing) - 1))
        if next_open is not None:
            text += self._step(next_open) if self.open == next_open else self._begin(next_open)
        return text

    def finish(self) -> str:
        """The lines after the run: the open stage's end (``failed`` where a job of it
        failed, ``stopped`` where the run stopped before it was done), a line for each stage
        that failed before its line began, or ``Nothing to be done``."""
        if self.failed or self.errors:
            failed = {self._failed_stage(job) for job in self.failed} - {None}
            text = ""
            if self.open:
                text += self._end("failed" if self.open in failed else "stopped")
            for stage in self.stages:
                if stage in failed and stage not in self.shown:
                    text += self._begin(stage) + self._end("failed")
            return text
        done, total = self.totals()
        if self.nothing or (self.seen_plan and total == 0):
            text = ""
            for stage in PLAIN_STAGES[:1]:
                if stage in self.stages and stage not in self.shown:
                    text += f"{self.label(stage)} ... up to date\n"
                    self.shown.append(stage)
            return text + "Nothing to be done: every result is up to date\n"
        if done >= total and self.seen_plan:
            return self.advance(final=True)
        return self._end("stopped") if self.open else ""

    def _failed_stage(self, job: dict):
        stage = self.job_stages.get(job.get("jobid"))
        return stage or rule_stage(job["rule"], self.stages)

    def plan_lines(self) -> str:
        """A dry run's plan: one line per stage with its jobs per rule, and the total;
        nothing when Snakemake stopped before it planned (a refused config: its error says
        why)."""
        if self.nothing or (self.seen_plan and not self.totals()[1]):
            return "Nothing to be done: every result is up to date\n"
        if not self.seen_plan:
            return ""
        lines = []
        for stage in self.stages:
            n = self.planned.get(stage, 0)
            if not n:
                continue
            rules = ", ".join(
                f"{rule} {count}" for rule, count in self.rules.get(stage, {}).items() if count
            )
            lines.append(f"{self.label(stage)}: {_jobs(n)} ({rules})")
        lines.append(f"{_jobs(self.totals()[1])} in all (a dry run: nothing was run)")
        return "\n".join(lines) + "\n"

    # -- errors ---------------------------------------------------------------------------

    def job_logs(self) -> list:
        """The log files of the jobs that failed, each once."""
        return list(dict.fromkeys(p for job in self.failed for p in job["logs"]))

    def error_lines(self, ours=None) -> list:
        """One line per distinct error: each failed job's (the first error line of its
        log, :func:`log_error`, else ``rule X failed``), then Snakemake's own
        (:func:`exception_line`; ``ours`` are the exception names said without a name)."""
        ours = our_exceptions() if ours is None else ours
        messages = []
        for job in self.failed:
            message = next(filter(None, map(log_error, job["logs"])), None)
            messages.append(message or f"rule {job['rule']} failed")
        for error in self.errors:
            line = exception_line(error["message"], error["exception"], ours)
            if line:
                messages.append(line)
        return list(dict.fromkeys(" ".join(m.split()) for m in messages))

    def summary(self) -> dict:
        """What the run did, for the command that started it (JSON-serialisable)."""
        done, total = self.totals()
        return {
            "stages": list(self.shown),
            "done": done,
            "total": total,
            "nothing": self.nothing,
            "failed": self.failed,
            "errors": self.errors,
        }
