"""How a command follows a Snakemake run: through the logger plugin ``stereovar``
(:mod:`snakemake_logger_plugin_stereovar`, :mod:`stereovar.progress`), which writes one line
per stage to a pipe the command shows, Snakemake's whole output to the run's log file, and
at the end what the run did and which jobs failed to a JSON file (:class:`_Run`).

While a run's lines are quiet (a long job, nothing ends), the command says where the run
stood again, its estimate of the time left counted down (:class:`Heartbeat`): every
:data:`HEARTBEAT_S` in a log or a pipe, every :data:`LIVE_HEARTBEAT_S` on a terminal, where the
line is rewritten in place.

After the run, :meth:`_Run.errors` gives one line per error: each failed job's, from its log
file; else, for a run stopped before its jobs, Snakemake's refusal of its options, who holds
the lock that stopped it, the workflow's own ``stereovar:`` line, Snakemake's error or a full
disk, read from the end of the run's log; else the exit status.
"""

from __future__ import annotations

import os
import re
import sys

from ..eta import (
    SEPARATOR,
    format_duration,
    in_all,
    stage_count,
    time_left_in,
    time_left_text,
)
from ..progress import JOB_FAILED, exception_line, is_dry_run, job_error, log_error
from .console import PROG, isatty, say

#: The workflow's own one-line errors (``stereovar.errors.exit_with_one_line``), and the
#: lines it prints with the same prefix that are not errors (the command's own header among
#: them: ``stereovar: running ...``).
_WORKFLOW_LINE = "stereovar: "
_WORKFLOW_NOTES = ("warning:", "removed the lock", "running ")
#: Seconds of quiet after which a run's status is said again (:class:`Heartbeat`): in a log
#: or a pipe, where each is a line of its own; on a terminal, where the line is rewritten.
HEARTBEAT_S = 30.0
LIVE_HEARTBEAT_S = 5.0
#: argparse's last line when it refuses a command line: ``<program>: error: <message>``.
_USAGE_ERROR = re.compile(r"\S+: error: (.+)")
#: How much of the end of the run's log is read for the errors of a run that stopped early.
_TAIL_BYTES = 64 * 1024
#: The exit status of a run stopped by Ctrl-C (SIGINT), as a shell gives it: 128 + 2.
INTERRUPTED_STATUS = 130
#: The one line said for it.
INTERRUPTED = (
    "interrupted (Ctrl-C): the results that were finished are kept and the jobs that were "
    "stopped run again; run the same command again to go on"
)
#: The files in the temporary folder through which the plugin hands a run's summary to the
#: command (:meth:`_Run.run`): ``stereovar-run-<pid>-<random>.json``, ``<pid>`` the command's.
SUMMARY_PREFIX = "stereovar-run-"
#: Age (s) after which a summary file that names no process (written by an older stereovar)
#: is removed.
_UNNAMED_SUMMARY_AGE = 24 * 3600


def clean_stale_summaries(folder=None) -> list:
    """Remove this user's run summaries (:data:`SUMMARY_PREFIX`) left in the temporary folder
    by commands that were killed: those whose process is gone, and those that name no
    process and are older than a day. A run's summary is written by the plugin as the run
    ends and read at once, so removing one of a process that still runs costs nothing.

    Parameters
    ----------
    folder : path-like, optional
        Default: the temporary folder (:func:`tempfile.gettempdir`).

    Returns
    -------
    list of Path
        The files removed.
    """
    import re
    import tempfile
    import time
    from pathlib import Path

    from ..processes import process_exists

    removed = []
    for path in Path(folder or tempfile.gettempdir()).glob(f"{SUMMARY_PREFIX}*.json"):
        try:
            st = path.lstat()
            if not path.is_file() or path.is_symlink() or st.st_uid != os.getuid():
                continue
            named = re.fullmatch(rf"{SUMMARY_PREFIX}(\d+)-.+\.json", path.name)
            gone = (
                not process_exists(int(named.group(1)))
                if named
                else time.time() - st.st_mtime > _UNNAMED_SUMMARY_AGE
            )
            if gone:
                path.unlink()
                removed.append(path)
        except OSError:
            continue
    return removed


def workflow_error(lines) -> str | None:
    """The workflow's last ``stereovar: <message>`` line (it stopped with it), without the
    prefix; lines with that prefix that are not errors are passed over.

    Examples
    --------
    >>> workflow_error(["stereovar: removed the lock of an earlier run that was killed",
    ...                 "stereovar: config key 'spp': 0 is too small"])
    "config key 'spp': 0 is too small"
    """
    for line in reversed(list(lines)):
        if line.startswith(_WORKFLOW_LINE):
            message = line[len(_WORKFLOW_LINE) :].strip()
            if message and not message.startswith(_WORKFLOW_NOTES):
                return message
    return None


def usage_error(lines) -> str | None:
    """Snakemake's refusal of its options (argparse's ``usage: ...`` then ``<program>: error:
    <message>``) as one line that says where the options are listed; None without one.

    Parameters
    ----------
    lines : iterable of str
        Snakemake's output, or its end.

    Returns
    -------
    str or None

    Examples
    --------
    >>> usage_error(["usage: snakemake [-h] ...", "   [targets ...]",
    ...              "snakemake: error: unrecognized arguments: --dryrunn"])  # doctest: +ELLIPSIS
    'snakemake refused its options: unrecognized arguments: --dryrunn (stereovar run and ...)'
    """
    lines = [line.rstrip("\n") for line in lines]
    if not any(line.startswith("usage: ") for line in lines):
        return None
    for line in reversed(lines):
        match = _USAGE_ERROR.fullmatch(line.strip())
        if match:
            return (
                f"snakemake refused its options: {match.group(1)} ({PROG} run and report pass "
                f"the options they do not take to snakemake; {PROG} run --help and snakemake "
                "--help list them)"
            )
    return None


def raised_error(lines, where=".") -> str | None:
    """The last ``SomeError: message`` line of a traceback in ``lines`` (a full disk said
    as such, with the free space of ``where``), else None."""
    import re

    raised = [
        m
        for m in (re.fullmatch(r"(\w*(?:Error|Exception)): (.+)", ln.strip()) for ln in lines)
        if m and m.group(1) not in JOB_FAILED
    ]
    if not raised:
        return None
    kind, message = raised[-1].groups()
    if "[Errno 28]" in message:  # ENOSPC: Snakemake's lock or records, or a job's output
        import shutil

        free = shutil.disk_usage(where).free / 10**6
        return (
            f"the disk of {where} is full ({free:.1f} MB free; Snakemake stopped with "
            f"{kind}: {message}); free space on it, then run the same command again"
        )
    return f"{kind}: {message}"


class Heartbeat:
    """What a command says while a run's lines are quiet: the open stage's line again, with
    where the run stood (the stage's count, the run's, read from the lines so far), its
    estimate of the time left counted down, and how long ago the last line came.

    It reads only the text the logger plugin writes, and its times are given, so that what
    it says follows from the lines and their times alone.

    Parameters
    ----------
    live : bool
        The lines are rewritten in place (a terminal): the heartbeat rewrites the open line
        too; else it ends the open line with the status and begins it again.
    every : float, optional
        Seconds of quiet between two heartbeats (default :data:`LIVE_HEARTBEAT_S` live, else
        :data:`HEARTBEAT_S`).
    """

    def __init__(self, live: bool = False, every: float | None = None):
        self.live = live
        self.every = every or (LIVE_HEARTBEAT_S if live else HEARTBEAT_S)
        self.line = ""  # the open line as the plugin wrote it (live: as rewritten last)
        self.count = ("", "")  # the label of the line that last said its stage's count, and it
        self.in_all = ""  # the run's count the lines said last
        self.left = None  # the time left they said last (s), and when
        self.left_at = 0.0
        self.last = None  # when the plugin wrote last
        self.said = None  # when the heartbeat said something last

    def seen(self, text: str, now: float) -> None:
        """The plugin wrote ``text`` at ``now``."""
        self.last = now
        for piece in re.split(r"(\n)", text):
            if piece == "\n":
                self._read(self.line, now)
                self.line = ""
            elif piece:
                self.line = (self.line + piece).rsplit("\r\x1b[K", 1)[-1]
        if self.line:
            self._read(self.line, now)

    def _read(self, line: str, now: float) -> None:
        count = in_all(line)
        if count:
            self.in_all = count
            self.left, self.left_at = time_left_in(line), now
        label, begun, body = line.partition(" ... ")
        if begun and stage_count(body):
            self.count = (label, stage_count(body))

    def _since(self, now: float) -> float:
        """When the plugin or the heartbeat last wrote (``now`` before either did)."""
        return max((t for t in (self.last, self.said) if t is not None), default=now)

    def wait(self, now: float) -> float:
        """Seconds until a heartbeat may be due."""
        return max(self._since(now) + self.every - now, 0.05)

    def due(self, now: float) -> str:
        """The text to write at ``now``: ``""`` unless :attr:`every` seconds have passed since
        the plugin or the heartbeat last wrote and a stage's line is open."""
        label, begun, _ = self.line.partition(" ... ")
        if not begun or self.last is None or now - self._since(now) < self.every:
            return ""
        parts = [self.count[1] if self.count[0] == label else "", self.in_all]
        if self.left is not None:
            parts.append(time_left_text(self.left - (now - self.left_at)))
        parts.append(f"last change {format_duration(now - self.last)} ago")
        body = SEPARATOR.join(part for part in parts if part)
        self.said = now
        if self.live:
            return f"\r\x1b[K{label} ... {body}"
        return f"{body}\n{label} ... "


def _default_sigint():
    """Make Ctrl-C raise :class:`KeyboardInterrupt` while a run goes on, whatever handler
    the process had (a host that embeds the command, a library that set its own), and
    return that handler to restore; None off the main thread, where no handler can be set."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return None
    return signal.signal(signal.SIGINT, signal.default_int_handler)


class _Run:
    """One Snakemake run of a command, with the logger plugin ``stereovar``.

    Snakemake's whole output goes to ``log`` (a new file: the command's record of the run);
    the plugin's lines go to stderr (a dry run's plan to stdout); ``verbose``, Snakemake's
    whole output goes to stderr as well, and no stage lines.

    Parameters
    ----------
    log : path-like
        The run's log file, created by the caller (never one that exists).
    stages : str
        ``run`` or ``audit`` (:data:`stereovar.progress.STAGE_MAPS`).
    import_label, source : str
        The audit's import line and renderer wildcard.
    verbose : bool
        Show Snakemake's whole output live.
    command : str
        The stereovar command line, for the record of the run (:mod:`stereovar.preflight`).
    """

    def __init__(
        self,
        log,
        *,
        stages: str = "run",
        import_label: str = "",
        source: str = "",
        verbose: bool = False,
        command: str = "",
    ):
        self.log = log
        self.stages, self.import_label, self.source = stages, import_label, source
        self.verbose, self.command = verbose, command
        self.root = None  # the folder Snakemake runs in
        self.configfiles: list = []  # its --configfile options
        self.summary: dict = {}  # what the plugin wrote as the run ended
        self.log_error = None  # why the log stopped being written, if it did
        self.interrupted = False  # the user pressed Ctrl-C while the run went on
        self._partial = False  # the lines shown end inside a line (a stage's, begun)
        self.heartbeat_s = None  # seconds of quiet between heartbeats (None: Heartbeat's)

    # -- running ----------------------------------------------------------------------------

    def plugin_options(self, progress_fd: int, summary: str) -> list:
        """Snakemake's options that select the plugin and set it for this run."""
        options = [
            "--logger=stereovar",
            f"--logger-stereovar-stages={self.stages}",
            f"--logger-stereovar-summary={summary}",
            f"--logger-stereovar-progress-fd={progress_fd}",
        ]
        if self.import_label:
            options.append(f"--logger-stereovar-import-label={self.import_label}")
        if self.source:
            options.append(f"--logger-stereovar-source={self.source}")
        if self.verbose:
            options.append("--logger-stereovar-verbose")
        else:
            options.append(f"--logger-stereovar-log={os.path.abspath(self.log)}")
        if isatty(sys.stderr):
            options.append("--logger-stereovar-live")
        return options

    def run(self, cmd: list, root) -> int:
        """Run ``cmd`` (Snakemake) in ``root`` with the plugin's options added, showing its
        lines as they come; the Snakemake process is recorded in ``root/.snakemake`` while
        it runs (:func:`stereovar.preflight.record_run`), so that another run it locks out
        can say which process holds the lock. Returns its exit status."""
        import json
        import subprocess
        import tempfile
        from pathlib import Path

        from ..preflight import STATE_DIR, forget_run, record_run

        self.root = Path(root)
        self.configfiles = [cmd[k + 1] for k, arg in enumerate(cmd[:-1]) if arg == "--configfile"]
        header = "stereovar: running " + " ".join(cmd[1:]) + "\n"
        self._write(header)
        if self.verbose:
            sys.stderr.write(header)
        read, write = os.pipe() if not self.verbose else (None, None)
        clean_stale_summaries()
        handle, summary = tempfile.mkstemp(prefix=f"{SUMMARY_PREFIX}{os.getpid()}-", suffix=".json")
        os.close(handle)
        shown = sys.stdout if is_dry_run(cmd[1:]) else sys.stderr
        env = {**os.environ, "PYTHONUNBUFFERED": "1", "PYTHONIOENCODING": "utf-8"}
        previous = _default_sigint()
        try:
            with open(self.log, "a", encoding="utf-8") as out:
                proc = subprocess.Popen(
                    [*cmd, *self.plugin_options(2 if write is None else write, summary)],
                    cwd=root,
                    env=env,
                    stdout=subprocess.PIPE if self.verbose else out,
                    stderr=subprocess.STDOUT,
                    pass_fds=() if write is None else (write,),
                )
            record = None
            try:  # a Ctrl-C from here on, however early, stops the run as an interruption
                if write is not None:
                    os.close(write)
                    write = None
                try:
                    record = record_run(self.root / STATE_DIR, proc.pid, self.command)
                except OSError:  # the record only names the process: the run goes on
                    record = None
                if self.verbose:
                    self._tee(proc.stdout)
                else:  # a dry run's plan comes at its end: nothing to say meanwhile
                    quiet = shown is sys.stderr
                    beat = Heartbeat(isatty(sys.stderr), self.heartbeat_s) if quiet else None
                    self._show(read, shown, beat)
            except KeyboardInterrupt:  # Snakemake got it too: let it stop, keep what it says
                self.interrupted = True
                if write is not None:  # so that its lines end when Snakemake does
                    os.close(write)
                    write = None
                if self.verbose:
                    self._tee(proc.stdout, show=False)
                else:  # its stage lines would say its jobs failed: the interruption says why
                    self._drain(read)
                    if self._partial:
                        shown.write("\n")
            finally:
                rc = self._wait(proc)
                if record is not None:
                    forget_run(record)
            try:
                self.summary = json.loads(Path(summary).read_text() or "{}")
            except (OSError, ValueError):
                self.summary = {}
        finally:
            for fd in (read, write):
                if fd is not None:
                    os.close(fd)
            Path(summary).unlink(missing_ok=True)
            if previous is not None:
                import signal

                signal.signal(signal.SIGINT, previous)
        self.log_error = self.log_error or self.summary.get("log_error")
        return INTERRUPTED_STATUS if self.interrupted and rc else rc

    def _wait(self, proc) -> int:
        """Wait for Snakemake to end, through more Ctrl-C presses (it stops its jobs)."""
        while True:
            try:
                return proc.wait()
            except KeyboardInterrupt:
                self.interrupted = True

    def _show(self, fd: int, stream, heartbeat: Heartbeat | None = None) -> None:
        """Copy the plugin's lines from ``fd`` to ``stream`` until the run closes it; while
        they are quiet, what ``heartbeat`` says."""
        import codecs
        import select
        import time

        decoder = codecs.getincrementaldecoder("utf-8")("replace")
        while True:
            if heartbeat is not None:
                wait = heartbeat.wait(time.monotonic())
                if not select.select([fd], [], [], wait)[0]:
                    self._say(stream, heartbeat.due(time.monotonic()))
                    continue
            chunk = os.read(fd, 4096)
            if not chunk:
                break
            text = decoder.decode(chunk)
            self._say(stream, text)
            if heartbeat is not None:
                heartbeat.seen(text, time.monotonic())
        stream.write(decoder.decode(b"", final=True))

    def _say(self, stream, text: str) -> None:
        """Show ``text``, keeping whether the lines shown end inside a line."""
        if text:
            stream.write(text)
            stream.flush()
            self._partial = not text.endswith("\n")

    @staticmethod
    def _drain(fd: int) -> None:
        """Read ``fd`` until the run closes it, showing nothing."""
        while os.read(fd, 4096):
            pass

    def _tee(self, output, show: bool = True) -> None:
        """Snakemake's whole output, live (``-v``): to stderr and to the log."""
        for raw in output:
            line = raw.decode("utf-8", "replace")
            self._write(line)
            if show:
                sys.stderr.write(line)
                sys.stderr.flush()
        output.close()

    def _write(self, text: str) -> None:
        """Append to the log file; once that fails (a full disk), the run goes on and
        :attr:`log_error` says why the log ends early."""
        if self.log_error is not None:
            return
        try:
            with open(self.log, "a", encoding="utf-8") as out:
                out.write(text)
        except OSError as err:
            self.log_error = err.strerror or str(err)

    # -- errors -----------------------------------------------------------------------------

    def job_logs(self) -> list:
        """The log files of the jobs that failed (none for a run stopped by Ctrl-C: its
        jobs were stopped, they did not fail)."""
        if self.interrupted:
            return []
        return list(dict.fromkeys(p for job in self.summary.get("failed", []) for p in job["logs"]))

    def _tail(self) -> list:
        try:
            with open(self.log, "rb") as log:
                log.seek(0, os.SEEK_END)
                log.seek(max(0, log.tell() - _TAIL_BYTES))
                return log.read().decode("utf-8", "replace").splitlines()
        except OSError:
            return []

    def errors(self, rc: int) -> list:
        """One line per distinct error of a failed run (see the module's docstring); one
        line for a run stopped by Ctrl-C (its jobs' failures are the interruption's)."""
        from ..progress import our_exceptions

        if self.interrupted:
            return [INTERRUPTED]

        tail = self._tail()
        messages = []
        failed = self.summary.get("failed", [])
        for job in failed:
            message = next(filter(None, map(log_error, job["logs"])), None)
            messages.append(message or f"rule {job['rule']} failed")
        if failed and not any(map(log_error, self.job_logs())):
            # no log says why: the jobs' own error lines in Snakemake's output
            messages = list(dict.fromkeys(filter(None, map(job_error, tail)))) or messages
        if not messages:
            ours = our_exceptions()
            reported = self.summary.get("errors", [])
            events = (exception_line(e["message"], e["exception"], ours) for e in reported)
            messages = [
                usage_error(tail)
                or self._locked(tail)
                or workflow_error(tail)
                or next(filter(None, events), None)
                or raised_error(tail, self.root or ".")
                or f"snakemake stopped with exit status {rc}"
            ]
        return list(dict.fromkeys(" ".join(m.split()) for m in messages))

    def refusal(self) -> str | None:
        """Snakemake's refusal of its options (:func:`usage_error`), where it stopped so
        before the run began; else None."""
        return None if self.summary else usage_error(self._tail())

    def _locked(self, tail) -> str | None:
        """Who holds the lock, when Snakemake stopped because the folder is locked."""
        exceptions = [e.get("exception") for e in self.summary.get("errors", [])]
        locked = "LockException" in exceptions or any(
            line.startswith("LockException") for line in tail
        )
        if self.root is None or not locked:
            return None
        import shlex

        from ..preflight import STATE_DIR, lock_message

        configs = [arg for f in self.configfiles for arg in ("--configfile", f)]
        unlock = shlex.join([PROG, "run", *configs, "--", "--unlock"])
        return lock_message(self.root / STATE_DIR, unlock)

    def report(self, rc: int) -> None:
        """After the run: a warning if the log ends early; a failed run's errors, one line
        each."""
        if self.log_error:
            say(f"warning: the log ends early: {self.log_error}")
        if rc != 0:
            for message in self.errors(rc):
                say(f"{PROG}: error: {message}")


def log_line(shown_log: str, jobs=()) -> str:
    """``log: <the run's log> (the failed job's: <its logs>)``."""
    return f"log: {shown_log}" + (f" (the failed job's: {', '.join(jobs)})" if jobs else "")
