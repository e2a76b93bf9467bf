"""Progress of a run from Snakemake's log events (stereovar.progress and the logger plugin
snakemake_logger_plugin_stereovar): one line per stage, jobs done of planned, a failed job's
one-line error and the log files, a dry run's plan by stage.

The plugin's handler is driven with log records as Snakemake makes them (``logger.info(msg,
extra={"event": ..., ...})``, the fields read from snakemake/jobs.py, scheduling/
job_scheduler.py, workflow.py and exceptions.py); one tiny real ``snakemake --logger
stereovar`` run checks that Snakemake finds the plugin and hands it those events."""

import json
import logging
import os
import subprocess
import sys
from types import SimpleNamespace

import pytest
from snakemake_interface_logger_plugins.common import LogEvent

import snakemake_logger_plugin_stereovar as plugin
from stereovar import progress
from stereovar.progress import AUDIT_STAGES, RUN_STAGES, Progress


def record(event=None, msg="", level=logging.INFO, **fields):
    """A log record as Snakemake's logger makes it: the event and its fields as attributes."""
    extra = {"event": event} if event is not None else {}
    return logging.makeLogRecord(
        {"name": "snakemake", "levelno": level, "levelname": logging.getLevelName(level),
         "msg": msg, "args": (), **extra, **fields}
    )


def job_info(jobid, rule, log=(), **wildcards):
    return record(LogEvent.JOB_INFO, f" Rule: {rule}, Jobid: {jobid}", jobid=jobid,
                  rule_name=rule, rule_msg=None, local=False, input=[], output=[],
                  log=list(log), benchmark=None, wildcards=wildcards, reason="Missing output",
                  resources={}, priority=0, threads=1, indent=False, is_checkpoint=False,
                  printshellcmd=True, is_handover=False, shellcmd=None)


def finished(jobid, rule):
    return record(LogEvent.JOB_FINISHED, f"Finished jobid: {jobid} (Rule: {rule})",
                  job_id=jobid)


def job_error(jobid, rule, log=()):
    return record(LogEvent.JOB_ERROR, f"Error in rule {rule}, jobid: {jobid}", logging.ERROR,
                  rule_name=rule, rule_msg=None, jobid=jobid, input=[], output=[],
                  log=list(log), conda_env=None, container_img=None, aux={}, indent=False,
                  shellcmd=None)


def run_info(**stats):
    return record(LogEvent.RUN_INFO, "Job stats: ...",
                  stats={**stats, "total": sum(stats.values())})


class Handler:
    """The plugin's handler with its progress lines going to a file; ``.lines()`` closes it
    and returns them."""

    def __init__(self, tmp_path, dryrun=False, **settings):
        self.path = tmp_path / f"progress-{len(list(tmp_path.iterdir()))}.txt"
        fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
        common = SimpleNamespace(dryrun=dryrun, verbose=False, quiet=None, printshellcmds=False)
        self.handler = plugin.LogHandler(
            common, plugin.LogHandlerSettings(progress_fd=fd, **settings)
        )

    def emit(self, *records):
        for rec in records:
            self.handler.handle(rec)
        return self

    def text(self) -> str:
        return self.path.read_text()

    def lines(self) -> list:
        self.handler.close()
        return self.text().splitlines()


def test_each_rule_of_the_workflow_has_a_stage_and_targets_none():
    assert progress.rule_stage("all", RUN_STAGES) is None
    for stages in (RUN_STAGES, AUDIT_STAGES):
        rules = [rule for names in stages.values() for rule in names]
        assert len(rules) == len(set(rules))  # no rule in two stages
        assert all(progress.rule_stage(rule, stages) in stages for rule in rules)
    assert list(RUN_STAGES)[:2] == ["scenes", "render"]
    assert progress.stage_map("audit") is AUDIT_STAGES
    with pytest.raises(ValueError, match="audit"):
        progress.stage_map("nope")


def test_options_that_run_nothing_get_snakemakes_own_output():
    assert progress.reports_progress(["-n"]) and progress.reports_progress([])
    assert not progress.reports_progress(["--unlock"])
    assert not progress.reports_progress(["--report=r.html"])
    assert progress.is_dry_run(["-np"]) and not progress.is_dry_run(["--notemp", "-p"])


def test_a_failed_jobs_error_is_its_logs_first_error_line(tmp_path):
    log = tmp_path / "job.log"
    log.write_text(
        "2026-01-01 10:00:00,001 INFO reading f00\n"
        "2026-01-01 10:00:01,002 ERROR error: f00/R/seed_002.exr: cannot read it (truncated)\n"
        "2026-01-01 10:00:01,003 ERROR error: a second\n"
    )
    assert progress.log_error(log) == "f00/R/seed_002.exr: cannot read it (truncated)"
    log.write_text("Traceback (most recent call last):\nKeyError: 'x'\n")
    assert progress.log_error(log) == "KeyError: 'x'"  # no error line: the last line
    assert progress.log_error(tmp_path / "missing.log") is None


def test_snakemakes_errors_are_one_line_without_the_jobs_summary():
    ours = progress.our_exceptions()
    assert "AuditError" in ours and "ConfigError" in ours
    text = 'AuditError in file "/wf/common.smk", line 40:\ndata/f00.exr: gone\n  File "x"'
    assert progress.exception_line(text, "AuditError", ours) == "data/f00.exr: gone"
    assert progress.exception_line("KeyError in line 3 of x:\n'a'\n", "KeyError") == (
        "KeyError: 'a'"
    )
    assert progress.exception_line("WorkflowError:\nAt least one job did not complete "
                                   "successfully.", "WorkflowError") is None
    failed = progress.exception_line("RuleException:\nCalledProcessError ...", "RuleException")
    assert failed is None


def test_stages_follow_the_planned_jobs_and_mitigated_copies_count_as_mitigations():
    p = Progress(AUDIT_STAGES, labels={"import": "import: 1 frame"}, source="audit/a")
    out = [p.plan({"audit_import": 1, "variance": 2, "audit_verdict": 1, "all": 1,
                   "total": 5})]
    assert out[-1] == "import: 1 frame ... "
    out += [p.job(1, "audit_import", {"scene": "f00"}), p.done(1)]
    assert out[-1] == "done\nstatistics ... "
    out += [p.job(2, "variance", {"renderer": "audit/a"}),
            p.job(3, "variance", {"renderer": "audit/a/denoise"}), p.done(2)]
    assert out[-1] == "done (1 job; 2 of 4 in all)\nmitigations ... "
    out += [p.done(3), p.job(4, "audit_verdict"), p.done(4), p.job(0, "all"), p.done(0)]
    assert "".join(out) + p.finish() == (
        "import: 1 frame ... done\n"
        "statistics ... done (1 job; 2 of 4 in all)\n"
        "mitigations ... done (1 job; 3 of 4 in all)\n"
        "verdict ... done\n"
    )
    assert p.summary()["done"] == p.summary()["total"] == 4 and p.error_lines() == []


def test_a_stage_that_fails_before_its_line_began_is_named():
    p = Progress(AUDIT_STAGES, labels={"import": "import: 1 frame"}, source="audit/a")
    out = p.plan({"audit_import": 1, "variance": 1, "transform": 1, "total": 3})
    out += p.job(1, "audit_import") + p.done(1)
    out += p.job(3, "transform", {"renderer": "audit/a", "transform": "sensor_only"})
    p.fail("transform", 3, ["logs/transform.log"])
    assert (out + p.finish()).splitlines() == [
        "import: 1 frame ... done",
        "statistics ... · mitigations started stopped",  # its one job never started
        "mitigations ... failed",
    ]
    assert p.job_logs() == ["logs/transform.log"]
    assert p.error_lines() == ["rule transform failed"]  # its log does not exist


def test_the_open_line_says_which_stage_runs_while_it_waits():
    """A frame's calibration runs while the second frame's import waits for a core: the
    import's line, open until that frame is imported, says so from the job events."""
    stats = {"audit_import": 2, "calibration_scene": 2, "audit_verdict": 1}
    events = [("job", 1, "audit_import"), ("done", 1), ("job", 2, "calibration_scene"),
              ("job", 3, "calibration_scene"), ("done", 2), ("job", 4, "audit_import"),
              ("done", 4), ("done", 3), ("job", 5, "audit_verdict"), ("done", 5)]

    def follow(live):
        p = Progress(AUDIT_STAGES, labels={"import": "import: 2 frames"}, live=live)
        shown = [p.plan({**stats, "total": 5})]
        for kind, jobid, *rule in events:
            shown.append(p.job(jobid, *rule) if kind == "job" else p.done(jobid))
        return shown + [p.finish()]

    text = "".join(follow(False))
    assert text.splitlines() == [
        "import: 2 frames ... 1/2 · calibration started 2/2 done",
        "calibration ... done (2 jobs; 4 of 5 in all)",
        "verdict ... done",
    ]
    live = follow(True)
    # once calibration's first job starts, the rewritten import line names it, with its count
    assert live[3].endswith("import: 2 frames ... frame 2 of 2 · running: calibration 0 of 2 "
                            "jobs")
    assert live[4].endswith("· running: calibration 0 of 2 jobs")  # its second job
    assert live[5].endswith("frame 2 of 2 · running: calibration 1 of 2 jobs")
    assert live[7].startswith("\r\x1b[Kimport: 2 frames ... done\n")  # frame 2 imported


def test_an_up_to_date_import_and_nothing_to_do_are_said():
    p = Progress(AUDIT_STAGES, labels={"import": "import: 2 frames"})
    p.nothing = True
    assert p.finish() == (
        "import: 2 frames ... up to date\nNothing to be done: every result is up to date\n"
    )
    p = Progress(AUDIT_STAGES, labels={"import": "import: 2 frames"})
    assert p.plan({"total": 0}) == "import: 2 frames ... up to date\n"  # --until, no job
    assert p.finish() == "Nothing to be done: every result is up to date\n"


def test_the_import_counts_its_frames(tmp_path):
    stats = {"audit_import": 3, "audit_verdict": 1}
    p = Progress(AUDIT_STAGES, labels={"import": "import: 3 frames"})
    text = p.plan({**stats, "total": 4})
    for k in (1, 2, 3):
        text += p.job(k, "audit_import") + p.done(k)
    assert text.splitlines()[0] == "import: 3 frames ... 1/3 2/3 3/3 done"
    # on a terminal the line is rewritten: frame k of n while frame k runs
    live = Progress(AUDIT_STAGES, labels={"import": "import: 3 frames"}, live=True)
    steps = [live.plan({**stats, "total": 4}), live.job(1, "audit_import"), live.done(1)]
    assert steps[0].endswith("import: 3 frames ... frame 1 of 3")
    assert steps[-1].endswith("import: 3 frames ... frame 2 of 3")
    steps += [live.job(2, "audit_import"), live.done(2), live.job(3, "audit_import"),
              live.done(3)]
    assert steps[-1].startswith("\r\x1b[Kimport: 3 frames ... done\n")


def test_the_handler_follows_snakemakes_events(tmp_path):
    log = tmp_path / "logs" / "results_page.log"
    log.parent.mkdir()
    log.write_text("2026-01-01 10:00:00,001 ERROR error: the claims table is missing\n")
    whole = tmp_path / "run.log"
    handler = Handler(tmp_path, log=str(whole)).emit(
        record(None, "Building DAG of jobs..."),
        run_info(render=2, variance=1, results_page=1, all=1),
        job_info(1, "render", scene="s0"), job_info(2, "render", scene="s1"),
        record(LogEvent.JOB_STARTED, "", jobs=[1, 2]),
        finished(1, "render"), record(LogEvent.PROGRESS, None, done=1, total=5),
        finished(2, "render"), record(LogEvent.PROGRESS, None, done=2, total=5),
        job_info(3, "variance"), finished(3, "variance"),
        job_info(4, "results_page", log=[str(log)]),
        job_error(4, "results_page", log=[str(log)]),
        record(LogEvent.ERROR, "WorkflowError:\nAt least one job did not complete "
               "successfully.", logging.ERROR, exception="WorkflowError"),
    )
    assert handler.text() == (  # written as the jobs end
        "render ... done (2 jobs; 2 of 4 in all)\n"
        "statistics ... done (1 job; 3 of 4 in all)\n"
        "pages ... "
    )
    assert handler.lines()[2:] == [
        "pages ... failed",
        "stereovar: error: the claims table is missing",
        f"log: {whole} (the failed job's: {log})",
    ]
    # Snakemake's whole output is the log's, as Snakemake's own handler formats it
    assert "Building DAG of jobs..." in whole.read_text()


def test_the_handler_leaves_errors_to_the_command_that_reads_its_summary(tmp_path):
    summary = tmp_path / "summary.json"
    lines = Handler(tmp_path, stages="audit", import_label="import: 1 frame",
                    summary=str(summary)).emit(
        run_info(audit_import=1, audit_verdict=1),
        job_info(1, "audit_import", log=["logs/f00.log"]),
        job_error(1, "audit_import", log=["logs/f00.log"]),
    ).lines()
    assert lines == ["import: 1 frame ... failed"]
    data = json.loads(summary.read_text())
    assert data["failed"] == [{"rule": "audit_import", "jobid": 1, "logs": ["logs/f00.log"]}]
    assert data["total"] == 2 and data["done"] == 0 and data["log_error"] is None


def test_a_dry_run_prints_its_plan_by_stage(tmp_path):
    lines = Handler(tmp_path, dryrun=True).emit(
        run_info(generate_scene=2, render=4, all=1),
        *[job_info(k, "render") for k in range(4)],
        job_info(5, "generate_scene"), job_info(6, "generate_scene"),
    ).lines()
    assert lines == [
        "scenes: 2 jobs (generate_scene 2)",
        "render: 4 jobs (render 4)",
        "6 jobs in all (a dry run: nothing was run)",
    ]
    nothing = Handler(tmp_path, dryrun=True).emit(
        record(None, "Nothing to be done (all requested files are present and up to date).")
    )
    assert nothing.lines() == ["Nothing to be done: every result is up to date"]


def test_verbose_writes_snakemakes_whole_output_instead(tmp_path):
    lines = Handler(tmp_path, verbose=True).emit(
        record(None, "Building DAG of jobs..."), run_info(render=1), finished(1, "render"),
    ).lines()
    assert lines[0] == "Building DAG of jobs..." and "Job stats: ..." in lines
    assert not any(" ... done" in line for line in lines)


TINY = """\
rule all:
    input: "page.html"

rule render:
    output: "render_{i}.txt"
    shell: "echo {wildcards.i} > {output}"

rule variance:
    input: expand("render_{i}.txt", i=range(2))
    output: "variance.txt"
    shell: "cat {input} > {output}"

rule results_page:
    input: "variance.txt"
    output: "page.html"
    log: "logs/page.log"
    shell: "echo '2026-01-01 00:00:00,000 ERROR error: no claims table' > {log}; exit 1"
"""


def test_snakemake_finds_the_plugin_and_reports_by_stage(tmp_path):
    (tmp_path / "Snakefile").write_text(TINY)
    proc = subprocess.run(
        [sys.executable, "-m", "snakemake", "-j1", "--logger=stereovar",
         "--logger-stereovar-log", "run.log"],
        cwd=tmp_path, capture_output=True, text=True,
    )
    assert proc.returncode == 1
    assert proc.stderr.splitlines() == [
        "render ... done (2 jobs; 2 of 4 in all)",
        "statistics ... done (1 job; 3 of 4 in all)",
        "pages ... failed",
        "stereovar: error: no claims table",
        "log: run.log (the failed job's: logs/page.log)",
    ], proc.stderr
    whole = (tmp_path / "run.log").read_text()
    assert "Job stats:" in whole and "Error in rule results_page:" in whole
