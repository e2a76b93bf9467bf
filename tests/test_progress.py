"""Progress of a run from Snakemake's log events (stereovar.progress and the logger plugin
snakemake_logger_plugin_stereovar): one line per stage, jobs done of planned, inside a long
stage where the run stands and the time it has left, a failed job's one-line error and the
log files, a dry run's plan by stage; and what the command says while the lines are quiet
(stereovar.cli.monitor.Heartbeat).

:class:`Progress` is driven with events at given times (its clock is a parameter); the
plugin's handler with log records as Snakemake makes them (``logger.info(msg,
extra={"event": ..., ...})``, the fields read from snakemake/jobs.py, scheduling/
job_scheduler.py, workflow.py and exceptions.py); one tiny real ``snakemake --logger
stereovar`` run checks that Snakemake finds the plugin and hands it those events."""

import json
import logging
import os
import re
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest
from snakemake_interface_logger_plugins.common import LogEvent

import snakemake_logger_plugin_stereovar as plugin
from stereovar import eta, progress
from stereovar.cli.monitor import Heartbeat, _Run
from stereovar.progress import AUDIT_STAGES, RUN_STAGES, Progress

REPO = Path(__file__).resolve().parents[1]


class Clock:
    """A clock that says ``t``, set by the test: events at known times."""

    def __init__(self, t=0.0):
        self.t = t

    def __call__(self):
        return self.t


def without_estimate(text: str) -> str:
    """``text`` without its estimates of the time left, which a run of real (instant) jobs
    says from the durations it measured."""
    return re.sub(r"; (about [^)]+ left|past the estimate)", "", text)


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


def workflow_rules() -> set:
    """Every rule the workflow defines: ``rule`` and ``checkpoint`` (at any indent) and
    ``use rule ... as NAME``, read from the Snakefile and ``workflow/rules``."""
    rules = set()
    for path in [REPO / "Snakefile", *sorted((REPO / "workflow" / "rules").rglob("*.smk"))]:
        text = path.read_text()
        rules |= set(re.findall(r"^\s*(?:rule|checkpoint) (\w+):", text, re.M))
        rules |= set(re.findall(r"^\s*use rule \w+ as (\w+)", text, re.M))
    return rules


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


def test_every_rule_of_the_workflow_is_named_in_a_stage():
    """No rule counts in a stage by default (statistics), where its jobs would hold that
    stage's line open: the run's map names each rule but the audit's own, which the audit's
    map names."""
    rules = workflow_rules()
    assert {"render", "audit_import", "probe_train_control", "dose_response_table"} <= rules
    run = {rule for names in RUN_STAGES.values() for rule in names}
    audit = {rule for names in AUDIT_STAGES.values() for rule in names}
    unnamed = rules - run - set(progress.TARGET_RULES)
    assert unnamed == {rule for rule in rules if rule.startswith("audit_")}
    assert unnamed <= audit
    assert audit <= rules and run <= rules  # and no stage names a rule that is gone


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


def test_a_job_counts_in_its_rules_stage_so_each_total_is_the_plans():
    """An audit with a mitigation: the variance job on the mitigated copy counts in
    statistics, as its rule does, so the statistics line counts 2 jobs from the plan on; the
    verdict's line, the last, says the run's count: all of it."""
    clock = Clock()
    p = Progress(AUDIT_STAGES, labels={"import": "import: 1 frame"}, source="audit/a",
                 clock=clock)
    out = [p.plan({"audit_import": 1, "variance": 2, "transform": 1, "audit_verdict": 1,
                   "all": 1, "total": 6})]
    assert out[-1] == "import: 1 frame ... "
    out += [p.job(1, "audit_import", {"scene": "f00"}), p.done(1)]
    assert out[-1] == "done\nstatistics ... "
    out += [p.job(2, "variance", {"renderer": "audit/a"}),
            p.job(3, "transform", {"renderer": "audit/a", "transform": "denoise"}), p.done(2)]
    assert out[-1] == ""  # the mitigated copy's variance is still to come
    assert p.planned == {"import": 1, "statistics": 2, "mitigations": 1, "verdict": 1}
    out += [p.done(3), p.job(4, "variance", {"renderer": "audit/a/denoise"}), p.done(4),
            p.job(5, "audit_verdict"), p.done(5), p.job(0, "all"), p.done(0)]
    assert "".join(out) + p.finish() == (
        "import: 1 frame ... done\n"
        "statistics ... done (2 jobs)\n"
        "mitigations ... done (1 job; 4 of 5 in all)\n"
        "verdict ... done (1 job; 5 of 5 in all)\n"
    )
    assert p.summary()["done"] == p.summary()["total"] == 5 and p.error_lines() == []


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
        clock = Clock()
        p = Progress(AUDIT_STAGES, labels={"import": "import: 2 frames"}, live=live,
                     clock=clock)
        shown = [p.plan({**stats, "total": 5})]
        for kind, jobid, *rule in events:
            clock.t += 2.0
            shown.append(p.job(jobid, *rule) if kind == "job" else p.done(jobid))
        return shown + [p.finish()]

    text = "".join(follow(False))
    assert text.splitlines() == [
        "import: 2 frames ... 1/2 · calibration started 2/2 done",
        "calibration ... done (2 jobs; 4 of 5 in all; about 5 s left)",
        "verdict ... done (1 job; 5 of 5 in all)",
    ]
    live = follow(True)
    # once calibration's first job starts, the rewritten import line names it, with its count
    assert live[3].endswith("import: 2 frames ... frame 2 of 2 · 1 of 5 in all · about 15 s "
                            "left · running: calibration 0 of 2 jobs")
    assert live[4].endswith("· running: calibration 0 of 2 jobs")  # its second job
    assert live[5].endswith("frame 2 of 2 · 2 of 5 in all · about 5 s left · running: "
                            "calibration 1 of 2 jobs")
    assert live[7].startswith("\r\x1b[Kimport: 2 frames ... done\n")  # frame 2 imported


def follow_run(jobs, *, live=False, tick=progress.TICK_S):
    """A run of ``jobs`` (rule, seconds) one at a time, planned in one ``RUN_INFO``, through a
    :class:`Progress` on a clock that the jobs' durations move; returns each event's text and
    the progress."""
    clock = Clock()
    stats = {}
    for rule, _ in jobs:
        stats[rule] = stats.get(rule, 0) + 1
    p = Progress(RUN_STAGES, clock=clock, live=live, tick=tick)
    shown = [p.plan({**stats, "all": 1, "total": len(jobs) + 1})]
    for jobid, (rule, seconds) in enumerate(jobs, 1):
        shown.append(p.job(jobid, rule))
        clock.t += seconds
        shown.append(p.done(jobid))
    shown += [p.job(0, "all"), p.done(0), p.finish()]
    return shown, p


#: A run whose render stage is long: 4 jobs of 20 s, one at a time.
LONG_RENDER = [("generate_scene", 5), *[("render", 20)] * 4, *[("variance", 2)] * 2,
               ("results_page", 1)]


def test_inside_a_long_stage_a_line_says_where_the_run_stands():
    """A job that ends 30 s or more after the last line says the stage's jobs done, the run's
    and the time left; the counts only grow, and the last line says all of the run's jobs."""
    shown, p = follow_run(LONG_RENDER)
    assert "".join(shown).splitlines() == [
        "scenes ... done (1 job; 1 of 8 in all; about 35 s left)",
        # t = 45 s, 40 s after the scenes' line: 85 s of jobs left at the pace so far
        "render ... 2 of 4 jobs · 3 of 8 in all · about 1 min 20 s left",
        "render ... done (4 jobs; 5 of 8 in all; about 50 s left)",
        "statistics ... done (2 jobs; 7 of 8 in all; about 15 s left)",
        "pages ... done (1 job; 8 of 8 in all)",
    ]
    assert p.summary()["done"] == p.summary()["total"] == 8
    every_count = [int(k) for k in re.findall(r"(\d+) of 8 in all", "".join(shown))]
    assert every_count == sorted(every_count) and every_count[-1] == 8
    # on a terminal the open line is rewritten with that status at every event
    live, _ = follow_run(LONG_RENDER, live=True)
    steps = [s.rsplit("\r\x1b[K", 1)[-1] for s in live if s]
    assert "render ... 1 of 4 jobs · 2 of 8 in all · about 1 min 40 s left" in steps
    assert "render ... 3 of 4 jobs · 4 of 8 in all · about 1 min 10 s left" in steps
    assert steps[-1] == "pages ... done (1 job; 8 of 8 in all)\n"


def test_stages_done_at_once_say_the_runs_count_once():
    """Render and ground truth finished while the scenes' last job ran: three lines at once,
    the last of them with the run's count, so no count is said twice."""
    clock = Clock()
    p = Progress(RUN_STAGES, clock=clock)
    text = p.plan({"generate_scene": 2, "render": 1, "ground_truth": 1, "variance": 1})
    for jobid, rule in enumerate(["generate_scene", "render", "ground_truth"], 1):
        text += p.job(jobid, rule)
    for jobid in (2, 3):
        clock.t += 5.0
        text += p.done(jobid)
    text += p.job(4, "generate_scene")
    for jobid in (1, 4):
        clock.t += 5.0
        text += p.done(jobid)
    assert text == (
        "scenes ... done (2 jobs)\n"
        "render ... done (1 job)\n"
        "ground truth ... done (1 job; 4 of 5 in all; about 5 s left)\n"
        "statistics ... "
    )


def test_the_estimate_is_the_measured_work_left_at_the_pace_so_far():
    pace = eta.Pace()
    planned = {"render": 2, "variance": 2}
    assert pace.left(planned, 0.0) is None  # nothing measured yet
    pace.start(1, "render", 0.0)
    pace.end(1, 10.0)
    pace.start(2, "render", 10.0)
    # one job at a time: the running render's 10 s less the 5 s it ran, and the two
    # variance jobs at the only measured cost, 10 s each
    assert pace.left(planned, 15.0) == pytest.approx(25.0)
    pace.end(2, 20.0)
    pace.start(3, "variance", 20.0)
    pace.end(3, 22.0)
    assert pace.left(planned, 22.0) == pytest.approx(2.0)  # variance now measured: 2 s
    # two jobs at a time: the run does work twice as fast as one job does
    side = eta.Pace()
    for jobid in (1, 2):
        side.start(jobid, "render", 0.0)
    for jobid in (1, 2):
        side.end(jobid, 10.0)
    for jobid in (3, 4):
        side.start(jobid, "render", 10.0)
    assert side.left({"render": 4}, 10.0) == pytest.approx(10.0)
    failed = eta.Pace()
    failed.start(1, "render", 0.0)
    failed.end(1, 10.0, failed=True)  # measures nothing
    assert failed.left({"render": 2}, 10.0) is None


def test_the_estimate_says_what_the_events_and_their_times_give():
    """The run of the tests above, its estimate at known times: after the second render
    (t = 45 s), 2 renders of 20 s, and 2 variance jobs and a page at the 15 s mean."""
    q = Progress(RUN_STAGES, clock=Clock())
    q.plan({"generate_scene": 1, "render": 4, "variance": 2, "results_page": 1})
    for jobid, (rule, seconds) in enumerate(LONG_RENDER[:3], 1):
        q.job(jobid, rule)
        q.clock.t += seconds
        q.done(jobid)
    assert q.time_left() == pytest.approx(2 * 20 + 2 * 15 + 15)
    assert q.status() == "2 of 4 jobs · 3 of 8 in all · about 1 min 20 s left"
    q.job(4, "render")
    q.clock.t += 25.0  # a render that takes longer than the others did: said to end now,
    # and the render to come takes at least as long
    assert q.time_left() == pytest.approx(1 * 25 + 2 * 15 + 15)
    assert eta.time_left_text(0.0) == eta.PAST_ESTIMATE
    last = eta.Pace()
    last.start(1, "render", 0.0)
    last.end(1, 10.0)
    last.start(2, "render", 10.0)
    assert last.left({"render": 2}, 30.0) is None  # only a job past its estimate is left


@pytest.mark.parametrize("seconds", [0, 4, 5, 42, 59, 60, 61, 290, 594, 600, 3599, 3725, 9000])
def test_a_duration_reads_back_as_it_was_said(seconds):
    said = eta.format_duration(seconds)
    back = eta.parse_duration(said)
    assert eta.format_duration(back) == said
    assert abs(back - seconds) <= max(5, 0.05 * seconds)


def test_the_heartbeat_says_the_status_again_counted_down_while_the_run_is_quiet():
    beat = Heartbeat(live=False, every=30.0)
    beat.seen("scenes ... done (1 job; 1 of 8 in all; about 35 s left)\nrender ... ", 5.0)
    assert beat.due(30.0) == ""  # 25 s of quiet
    # no status of the render line yet: the run's count and the estimate, counted down
    assert beat.due(35.0) == (
        "1 of 8 in all · about 5 s left · last change 30 s ago\nrender ... "
    )
    assert beat.due(50.0) == ""  # 15 s after the heartbeat
    assert beat.due(65.0) == "1 of 8 in all · past the estimate · last change 1 min ago\n" \
        "render ... "
    beat.seen("2 of 4 jobs · 3 of 8 in all · about 1 min 20 s left\nrender ... ", 70.0)
    assert beat.due(130.0) == (
        "2 of 4 jobs · 3 of 8 in all · about 20 s left · last change 1 min ago\nrender ... "
    )
    beat.seen("done (4 jobs; 5 of 8 in all; about 50 s left)\nstatistics ... ", 140.0)
    assert beat.due(170.0).startswith("5 of 8 in all · about 20 s left")  # another stage
    beat.seen("done (2 jobs; 8 of 8 in all)\n", 175.0)
    assert beat.due(300.0) == ""  # no line open: the run is between lines or done


def test_on_a_terminal_the_heartbeat_rewrites_the_open_line():
    beat = Heartbeat(live=True)
    assert beat.every == 5.0
    beat.seen("\r\x1b[Kimport: 3 frames ... frame 1 of 3 · 0 of 4 in all", 0.0)
    beat.seen("\r\x1b[Kimport: 3 frames ... frame 2 of 3 · 1 of 4 in all · about 50 s left"
              " · running: calibration 0 of 1 job", 10.0)
    assert beat.due(14.0) == ""
    assert beat.due(20.0) == ("\r\x1b[Kimport: 3 frames ... frame 2 of 3 · 1 of 4 in all · "
                              "about 40 s left · last change 10 s ago")
    assert beat.wait(20.0) == pytest.approx(5.0)


STAND_IN = r"""import os, sys, time
fd = int([a.split("=")[1] for a in sys.argv if a.startswith("--logger-stereovar-progress")][0])
os.write(fd, "render ... 2 of 4 jobs · 3 of 8 in all · about 1 min left\nrender ... ".encode())
time.sleep(1.0)
os.write(fd, b"done (4 jobs; 8 of 8 in all)\n")
"""


def test_a_quiet_run_gets_heartbeats_between_its_lines(tmp_path, capsys):
    """The command's own loop: a stand-in run writes a status, is quiet for a second, then
    ends its line; heartbeats come between, each ending the open line and beginning it
    again, so the run's lines stay whole."""
    log = tmp_path / "run.log"
    log.write_text("")
    run = _Run(log)
    run.heartbeat_s = 0.3
    started = time.monotonic()
    assert run.run([sys.executable, "-c", STAND_IN], tmp_path) == 0
    assert time.monotonic() - started >= 1.0
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "render ... 2 of 4 jobs · 3 of 8 in all · about 1 min left"
    assert lines[-1] == "render ... done (4 jobs; 8 of 8 in all)"
    beats = lines[1:-1]
    assert 1 <= len(beats) <= 4, lines
    for line in beats:
        assert re.fullmatch(r"render \.\.\. 2 of 4 jobs · 3 of 8 in all · about (1 min|55 s|50 s) "
                            r"left · last change 5 s ago", line), line


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
    assert steps[0].endswith("import: 3 frames ... frame 1 of 3 · 0 of 4 in all")
    assert re.search(r"import: 3 frames \.\.\. frame 2 of 3 · 1 of 4 in all( · about \d+ s "
                     r"left)?$", steps[-1])
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
    assert without_estimate(handler.text()) == (  # written as the jobs end
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
    assert without_estimate(proc.stderr).splitlines() == [
        "render ... done (2 jobs; 2 of 4 in all)",
        "statistics ... done (1 job; 3 of 4 in all)",
        "pages ... failed",
        "stereovar: error: no claims table",
        "log: run.log (the failed job's: logs/page.log)",
    ], proc.stderr
    whole = (tmp_path / "run.log").read_text()
    assert "Job stats:" in whole and "Error in rule results_page:" in whole
