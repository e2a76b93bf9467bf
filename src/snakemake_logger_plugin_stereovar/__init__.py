"""Snakemake logger plugin ``stereovar``: one line per stage of a run instead of Snakemake's
whole output.

Snakemake finds it by its module name (``snakemake_logger_plugin_<name>``) and uses it with
``snakemake --logger stereovar``; ``stereovar run`` and ``stereovar audit`` select it
themselves. It writes to the stream, so Snakemake adds no stream handler of its own: what the
terminal shows is the plugin's lines (:class:`stereovar.progress.Progress`), one per stage
(``render ... done (12 jobs; 14 of 30 in all)``), a dry run's plan by stage, and at the end
of a failed run each failed job's one-line error and the log files to read. Snakemake's
whole output, as its own stream handler formats it, goes to the file of ``--logger-stereovar-
log`` (appended, never truncated).

Settings (``--logger-stereovar-<name>``): ``stages`` (``run`` or ``audit``, which rules make
up which stage), ``import-label`` (the audit's import line), ``source`` (the audit's renderer
wildcard), ``log``, ``progress-fd`` (the file descriptor the lines go to; default stderr),
``live`` (rewrite the open line with counts, as on a terminal), ``verbose`` (Snakemake's
whole output on the stream instead of the lines) and ``summary`` (a JSON file for the
command that started the run: then the errors are left to that command to say).
"""

import json
import logging
import os
import sys
from dataclasses import dataclass, field

from snakemake_interface_logger_plugins.base import LogHandlerBase
from snakemake_interface_logger_plugins.common import LogEvent
from snakemake_interface_logger_plugins.settings import LogHandlerSettingsBase

#: What the error lines start with when the plugin says them itself.
PREFIX = "stereovar: error: "


@dataclass
class LogHandlerSettings(LogHandlerSettingsBase):
    stages: str = field(
        default="run",
        metadata={"help": "which stages to report: run (the workflow) or audit"},
    )
    import_label: str = field(
        default="", metadata={"help": "what the audit's import line says (default 'import')"}
    )
    source: str = field(
        default="",
        metadata={"help": "the audit's renderer wildcard: jobs on its mitigated copies "
                  "count as mitigations"},
    )
    log: str = field(
        default="",
        metadata={"help": "file to append Snakemake's whole output to"},
    )
    progress_fd: int = field(
        default=2, metadata={"help": "file descriptor for the progress lines (default 2)"}
    )
    live: bool = field(
        default=False,
        metadata={"help": "rewrite the open stage's line with its count (default: when "
                  "the progress descriptor is a terminal)"},
    )
    verbose: bool = field(
        default=False,
        metadata={"help": "write Snakemake's whole output to the progress descriptor, "
                  "not the stage lines"},
    )
    summary: str = field(
        default="",
        metadata={"help": "JSON file to write what the run did and why it failed to; the "
                  "error lines are then left to its reader"},
    )


class LogHandler(LogHandlerBase):
    """Follows Snakemake's log events with a :class:`stereovar.progress.Progress`."""

    def __post_init__(self) -> None:
        from stereovar.progress import Progress, stage_map

        settings = self.settings or LogHandlerSettings()
        self.options = settings
        self.dryrun = bool(getattr(self.common_settings, "dryrun", False))
        fd = int(settings.progress_fd)
        self.out = sys.stderr if fd == 2 else os.fdopen(fd, "w", encoding="utf-8", closefd=False)
        live = settings.live or _isatty(self.out)
        labels = {"import": settings.import_label} if settings.import_label else {}
        self.progress = Progress(
            stage_map(settings.stages), labels=labels, source=settings.source, live=live
        )
        self.log_file = None
        self.log_error = None  # why the log stopped being written, if it did
        if settings.log:
            try:
                self.log_file = open(settings.log, "a", encoding="utf-8")  # noqa: SIM115
            except OSError as err:
                self.log_error = err.strerror or str(err)
        self._last_job_info = False
        self._closed = False

    # -- what Snakemake asks of a logger plugin ---------------------------------------------

    @property
    def writes_to_stream(self) -> bool:
        return True  # in place of Snakemake's own stream handler

    @property
    def writes_to_file(self) -> bool:
        return False  # the log file is the command's record, not Snakemake's

    @property
    def has_filter(self) -> bool:
        return False

    @property
    def has_formatter(self) -> bool:
        return False

    @property
    def needs_rulegraph(self) -> bool:
        return False

    # -- events -----------------------------------------------------------------------------

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self._whole(record)
            text = self._follow(record)
            if text and not self.options.verbose and not self.dryrun:
                self._say(text)
        except Exception:
            self.handleError(record)

    def _follow(self, record: logging.LogRecord) -> str:
        """Hand one event to the progress; the text it returns."""
        from snakemake_interface_logger_plugins.common import LogEvent

        event = getattr(record, "event", None)
        progress = self.progress
        if event == LogEvent.RUN_INFO:
            return progress.plan(dict(getattr(record, "stats", {}) or {}))
        if event == LogEvent.JOB_INFO:
            return progress.job(
                record.jobid, record.rule_name, dict(getattr(record, "wildcards", {}) or {})
            )
        if event == LogEvent.JOB_FINISHED:
            return progress.done(record.job_id)
        if event == LogEvent.JOB_ERROR:
            progress.fail(record.rule_name, getattr(record, "jobid", None), record.log or [])
        elif event == LogEvent.GROUP_ERROR:
            for info in getattr(record, "job_error_info", []) or []:
                logs = list(info.get("log") or []) + list(getattr(record, "aux_logs", []) or [])
                progress.fail(info.get("rule_name"), info.get("jobid"), logs)
        elif event == LogEvent.ERROR:
            progress.error(record.getMessage(), getattr(record, "exception", ""))
        elif event is None and _nothing_to_be_done(record.getMessage()):
            progress.nothing = True
        return ""

    def _whole(self, record: logging.LogRecord) -> None:
        """Snakemake's own account of the record, as its stream handler writes it, to the
        log file (and, verbose, to the stream)."""
        if self.log_file is None and not self.options.verbose:
            return
        text = self.format(record)
        if text is None or text in ("", "None"):
            return
        if getattr(record, "event", None) == LogEvent.JOB_INFO:
            text = ("" if self._last_job_info else "\n") + text
            self._last_job_info = True
        else:
            self._last_job_info = False
        if self.options.verbose:
            self._say(text + "\n")
        if self.log_file is not None:
            try:
                self.log_file.write(text + "\n")
                self.log_file.flush()
            except OSError as err:  # a full disk: the run goes on, the log ends here
                self.log_error = err.strerror or str(err)
                self._close_log()

    def _say(self, text: str) -> None:
        try:
            self.out.write(text)
            self.out.flush()
        except (OSError, ValueError):  # the reader went away: the run goes on
            pass

    # -- the end ----------------------------------------------------------------------------

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            try:
                self._finish()
            finally:
                self._close_log()
                if self.out is not sys.stderr:
                    try:
                        self.out.close()
                    except OSError:
                        pass
        super().close()

    def _finish(self) -> None:
        progress = self.progress
        if not self.options.verbose:
            self._say(progress.plan_lines() if self.dryrun else progress.finish())
        if self.options.summary:
            summary = {**progress.summary(), "log_error": self.log_error}
            try:
                with open(self.options.summary, "w", encoding="utf-8") as out:
                    json.dump(summary, out)
            except OSError:
                pass
            return
        lines = [PREFIX + line for line in progress.error_lines()]
        logs = progress.job_logs()
        if self.options.log and (lines or logs):
            shown = f"log: {self.options.log}"
            lines.append(shown + (f" (the failed job's: {', '.join(logs)})" if logs else ""))
        elif logs:
            lines.append(f"the failed job's log: {', '.join(logs)}")
        if lines:
            self._say("\n".join(lines) + "\n")

    def _close_log(self) -> None:
        if self.log_file is not None:
            try:
                self.log_file.close()
            except OSError as err:
                self.log_error = self.log_error or err.strerror or str(err)
            self.log_file = None


def _isatty(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError, OSError):
        return False


def _nothing_to_be_done(message: str) -> bool:
    """Whether a plain message is Snakemake's "Nothing to be done" (its own constant)."""
    try:
        from snakemake.common import NOTHING_TO_BE_DONE_MSG
    except ImportError:  # driven without Snakemake itself (tests of the events)
        return str(message).startswith("Nothing to be done")
    return str(message) == NOTHING_TO_BE_DONE_MSG
