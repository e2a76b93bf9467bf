"""How a command follows a Snakemake run: through the logger plugin ``stereovar``
(:mod:`snakemake_logger_plugin_stereovar`, :mod:`stereovar.progress`), which writes one line
per stage to a pipe the command shows, Snakemake's whole output to the run's log file, and
at the end what the run did and which jobs failed to a JSON file (:class:`_Run`).

After the run, :meth:`_Run.errors` gives one line per error: each failed job's, from its log
file; else, for a run stopped before its jobs, who holds the lock that stopped it, the
workflow's own ``stereovar:`` line, Snakemake's error or a full disk, read from the end of
the run's log; else the exit status.
"""

from __future__ import annotations

import os
import sys

from ..progress import JOB_FAILED, exception_line, is_dry_run, job_error, log_error
from .snakemake import PROG, say

#: The workflow's own one-line errors (``stereovar.errors.exit_with_one_line``), and the
#: lines it prints with the same prefix that are not errors.
_WORKFLOW_LINE = "stereovar: "
_WORKFLOW_NOTES = ("warning:", "removed the lock")
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
        if _isatty(sys.stderr):
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
                else:
                    self._show(read, shown)
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

    def _show(self, fd: int, stream) -> None:
        """Copy the plugin's lines from ``fd`` to ``stream`` until the run closes it."""
        import codecs

        decoder = codecs.getincrementaldecoder("utf-8")("replace")
        while chunk := os.read(fd, 4096):
            text = decoder.decode(chunk)
            stream.write(text)
            stream.flush()
            if text:
                self._partial = not text.endswith("\n")
        stream.write(decoder.decode(b"", final=True))

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
                self._locked(tail)
                or workflow_error(tail)
                or next(filter(None, events), None)
                or raised_error(tail, self.root or ".")
                or f"snakemake stopped with exit status {rc}"
            ]
        return list(dict.fromkeys(" ".join(m.split()) for m in messages))

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


def _isatty(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError, OSError):
        return False


def log_line(shown_log: str, jobs=()) -> str:
    """``log: <the run's log> (the failed job's: <its logs>)``."""
    return f"log: {shown_log}" + (f" (the failed job's: {', '.join(jobs)})" if jobs else "")
