"""`stereovar audit` when the workflow would stop: the workflow's checks run before Snakemake
starts and give one line; the workflow's own line and a full disk reach the command's
stderr; a lock names the run that holds it, and only the lock of a run that is gone is
removed; cosmetic config edits import nothing again; a failed import says where the old
verdict went; the rebuild advice is a `stereovar run` command.

Most tests call the library, or the command with Snakemake replaced: by a stub that fails the
test if it is started (the pre-flight), or by a stand-in process that prints what Snakemake
prints when it stops (a lock, a failed job) and runs through the command's monitor as
Snakemake would. Snakemake itself runs twice: one import-only audit (module fixture
``imported``, a few seconds), after a run killed before its ``onstart`` left its lock, and
one dry run on it."""

import json
import os
import re
import shlex
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest
import yaml

from stereovar import cli, preflight
from stereovar import resources as sizing
from stereovar.audit import run as audit_run
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.config import validate_config
from stereovar.errors import AuditError, ConfigError, ImageError
from stereovar.io.store import RERUN_ARGS_ENV, rebuild_command
from stereovar.preflight import RUN_MARKER, RUNS_DIR, clear_stale_lock, stale_lock
from stereovar.transforms import TRANSFORMS

from .test_config_limits import read_only

PREVIOUS = "previous"

REPO = Path(__file__).resolve().parents[1]


def write_audit(root: Path, name: str = "t", *, render_format: str = "exr", **extra) -> str:
    """A one-frame synthetic audit (2 views x 4 seeds, 40 x 24) under ``root/data`` and its
    config ``root/<name>.yaml`` with ``extra`` audit settings; returns the config's name."""
    settings, _ = write_synthetic_audit(
        root / "data", name=name, n_frames=1, width=40, height=24, n_seeds=4,
        render_format=render_format,
    )
    settings["renders"] = f"data/renders/{{frame}}/{{view}}/seed_{{seed}}.{render_format}"
    settings["disparity"] = "data/disparity/{frame}.pfm"
    (root / f"{name}.yaml").write_text(yaml.safe_dump({"audit": {**settings, **extra}}))
    return f"{name}.yaml"


@pytest.fixture
def preflight_only(tmp_path, monkeypatch, capsys):
    """``run(*args)``: ``stereovar audit ARGS`` in ``tmp_path`` with Snakemake replaced by a
    stub that fails the test; returns the exit status and the stderr lines."""

    def never(args, root):
        raise AssertionError(f"snakemake started: {args}")

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(cli, "_snakemake", never)

    def run(*args):
        rc = cli.main(["audit", *args])
        captured = capsys.readouterr()
        assert captured.out == ""
        return rc, captured.err.splitlines()

    return run


def one_error(rc, err) -> str:
    assert rc == 2 and len(err) == 1, err
    assert err[0].startswith("stereovar: error: "), err
    return err[0]


# -- 1. the workflow's checks, before Snakemake starts ----------------------------------------


#: ``stereovar audit ARGS`` with Snakemake replaced by an exit that names it.
PREFLIGHT_ONLY = """import sys
from stereovar import cli
def never(args, root):
    sys.exit(f"snakemake started: {args}")
cli._snakemake = never
sys.exit(cli.main(["audit", *sys.argv[1:]]))
"""


def test_an_unwritable_audit_folder_stops_before_snakemake(tmp_path):
    config = write_audit(tmp_path)
    folder = tmp_path / "results" / "audit" / "t"
    folder.mkdir(parents=True)
    # not writable by this user: its permissions, or, for root, a read-only mount that only
    # the command's process sees
    prefix = read_only(folder)
    try:
        proc = subprocess.run(
            [*prefix, sys.executable, "-c", PREFLIGHT_ONLY, config],
            cwd=tmp_path, capture_output=True, text=True,
        )
    finally:
        folder.chmod(0o755)
    line = one_error(proc.returncode, proc.stderr.splitlines())
    fix = "chmod -R u+w" if prefix == () else "remount it read-write"
    assert line.startswith(f"stereovar: error: {folder} is ") and fix in line, line
    assert not (tmp_path / "logs").exists()  # nothing written, not even the log


def test_an_immutable_folder_is_named_with_the_attribute_to_clear(tmp_path):
    folder = tmp_path / "results"
    folder.mkdir()
    if os.geteuid() != 0 or shutil.which("chattr") is None or subprocess.run(
        ["chattr", "+i", str(folder)], capture_output=True
    ).returncode:
        pytest.skip("only root can set the immutable attribute, on a file system that has it")
    try:
        with pytest.raises(preflight.StereovarError) as err:
            preflight.check_writable([folder])
    finally:
        subprocess.run(["chattr", "-i", str(folder)], check=True)
    assert str(err.value).startswith(f"{folder} is immutable (chattr +i) and this run writes")
    assert f"chattr -i {folder}" in str(err.value)


@pytest.mark.parametrize(
    ("names", "needle"),
    [
        (["bogus"], "unknown mitigation 'bogus'"),
        (["spp_x4"], "'spp_x4' renders the scenes anew"),
        (["denoise", "shared_seed"], "'shared_seed' renders the scenes anew"),
    ],
)
def test_audit_mitigations_are_checked_before_snakemake(tmp_path, preflight_only, names, needle):
    line = one_error(*preflight_only(write_audit(tmp_path, mitigations=names)))
    assert "config key 'audit.mitigations'" in line and needle in line, line
    assert "mitigations.names" not in line
    offered = re.search(r"use store transforms (?:only )?\(([^)]*)\)", line)  # instead
    assert offered and sorted(offered.group(1).split(", ")) == sorted(TRANSFORMS), line


def test_renders_too_large_for_memory_stop_before_snakemake(tmp_path, preflight_only, monkeypatch):
    config = write_audit(tmp_path, render_format="pfm")
    for render in (tmp_path / "data" / "renders").rglob("*.pfm"):
        render.write_bytes(b"PF\n30000 30000\n-1\n")  # the header of a 30000 x 30000 image
    monkeypatch.setattr(sizing, "machine_mem_mb", lambda: 16000)
    line = one_error(*preflight_only(config))
    request = sizing.analysis_mem_mb(30000, 30000, sizing.ANALYSIS_IMAGES_MAX)
    assert "audit.renders: the renders are 30000x30000 pixels" in line, line
    assert f"{request:,} MB" in line and "16,000 MB of this machine's memory" in line
    assert "config key 'resolution'" not in line and "downsample" in line


#: Memory of an analysis job on 1x1 images by hand: 1024 MB and 24 float64 RGB pixels.
SMALLEST_ANALYSIS_MB = 1024 + 1
#: ... and of a render or moments job: 1536 MB and well under 1 MiB of pixels.
SMALLEST_RENDER_MB = 1536 + 1


@pytest.mark.parametrize(
    ("source", "fix"),
    [
        ("--resources mem_mb", "raise --resources mem_mb to at least {:,} MB"),
        ("cluster.max_mem_mb", "raise cluster.max_mem_mb to at least {:,} MB"),
        (sizing.MACHINE, "run on a machine with at least {:,} MB of memory (on a cluster, set "
         "cluster.max_mem_mb to the memory of its largest node)"),
    ],
)
def test_a_bound_no_image_size_fits_names_how_to_raise_it(tmp_path, monkeypatch, source, fix):
    monkeypatch.chdir(tmp_path)
    config = cli._workflow_config(tmp_path, [tmp_path / write_audit(tmp_path)])
    discovery = audit_run.discover_audit(config["audit"])
    config.update(audit_run.audit_run_config(config, discovery))
    with pytest.raises(AuditError) as err:
        audit_run.check_audit_memory(config, discovery, 1000, source)
    assert str(err.value).endswith(f"; no image size fits; {fix.format(SMALLEST_ANALYSIS_MB)}")
    default = validate_config({}, REPO / "workflow" / "schemas" / "config.schema.yaml")
    with pytest.raises(ConfigError) as err:
        sizing.check_job_memory(default, 1000, source)
    assert str(err.value).endswith(f"; no resolution fits; {fix.format(SMALLEST_RENDER_MB)}")


def test_a_full_disk_stops_before_snakemake(tmp_path, preflight_only, monkeypatch):
    config = write_audit(tmp_path)
    usage = shutil.disk_usage(tmp_path)
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage._replace(free=2 * 10**6))
    line = one_error(*preflight_only(config))
    assert f"the disk of {tmp_path} is full (2.0 MB free" in line and "free space" in line


def monitor_of(tmp_path, lines):
    """The audit's run monitor after a Snakemake whose output (its log) was ``lines``."""
    log = tmp_path / "run.log"
    log.write_text("".join(line + "\n" for line in lines))
    monitor = cli._Run(log)
    monitor.root = tmp_path
    return monitor


def test_the_workflow_line_and_a_full_disk_traceback_reach_stderr(tmp_path):
    monitor = monitor_of(tmp_path, [
        "Building DAG of jobs...",
        "stereovar: removed the lock of an earlier run that was killed",
        "stereovar: config key 'audit.mitigations': unknown mitigation 'bogus'; use store "
        "transforms (denoise)",
    ])
    assert monitor.errors(1) == [
        "config key 'audit.mitigations': unknown mitigation 'bogus'; use store transforms "
        "(denoise)"
    ]
    monitor = monitor_of(tmp_path, [
        "Building DAG of jobs...",
        "OSError: [Errno 28] No space left on device",
        "During handling of the above exception, another exception occurred:",
        "Traceback (most recent call last):",
        '  File "snakemake/persistence/file.py", line 255, in _write_locks',
        "    with open(lockfile, 'w') as lock:",
        "OSError: [Errno 28] No space left on device",
    ])
    (message,) = monitor.errors(1)
    assert message.startswith(f"the disk of {tmp_path} is full (") and "free space" in message


# -- 3. the lock names its holder ---------------------------------------------------------------


def ended_process() -> int:
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    return int(proc.stdout)


def locked_state(tmp_path) -> Path:
    state = tmp_path / ".snakemake"
    (state / "locks").mkdir(parents=True)
    (state / "locks" / "0.output.lock").write_text("results/x\n")
    return state


def test_a_record_written_as_a_run_starts_tells_a_live_lock_from_a_stale_one(tmp_path):
    state = locked_state(tmp_path)
    record = preflight.record_run(state, ended_process(), "stereovar audit a.yaml")
    assert stale_lock(state)  # killed before it could write the marker: its lock is stale
    host = json.loads(record.read_text())["host"]
    with subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"]) as live:
        try:
            # the marker names a run that is gone, a record a run still going: not stale
            (state / RUN_MARKER).write_text(json.dumps({"host": host, "pid": ended_process()}))
            preflight.record_run(state, live.pid, "stereovar audit a.yaml")
            assert not stale_lock(state) and not clear_stale_lock(state)
            assert (state / "locks" / "0.output.lock").exists()
        finally:
            live.kill()
    assert clear_stale_lock(state) and not any((state / "locks").iterdir())


def test_a_lock_with_only_this_runs_own_start_record_is_not_stale(tmp_path):
    # the workflow is parsed in the very process stereovar recorded as it started, before
    # that process takes its lock: a lock there is another run's, recorded nowhere (a plain
    # snakemake that has not reached onstart)
    state = locked_state(tmp_path)
    preflight.record_run(state, os.getpid(), "stereovar audit a.yaml")
    assert not stale_lock(state) and not clear_stale_lock(state)
    assert (state / "locks" / "0.output.lock").exists()


def test_a_killed_runs_start_record_stays_until_the_next_run_holds_the_lock(tmp_path):
    state = locked_state(tmp_path)
    killed = preflight.record_run(state, ended_process(), "stereovar audit a.yaml")
    mine = preflight.record_run(state, os.getpid(), "stereovar audit a.yaml")
    assert killed.exists()  # the next run's parse still sees the run that was killed
    assert stale_lock(state) and clear_stale_lock(state)
    preflight.mark_run(state)  # the next run holds the lock now
    assert not killed.exists() and mine.exists()


def test_a_lock_newer_than_the_marker_of_an_ended_run_is_not_stale(tmp_path):
    state = locked_state(tmp_path)
    lock, marker = state / "locks" / "0.output.lock", state / RUN_MARKER
    marker.write_text(json.dumps({"host": socket.gethostname(), "pid": ended_process()}))
    # the marker's run ended; a later run took the lock and has not reached onstart
    os.utime(marker, (lock.stat().st_mtime - 60,) * 2)
    assert not stale_lock(state) and not clear_stale_lock(state) and lock.exists()
    unlock = "stereovar run -- --unlock"
    assert "no record" in preflight.lock_message(state, unlock)
    os.utime(lock, (marker.stat().st_mtime - 60,) * 2)  # the marker's run took this lock
    assert stale_lock(state)
    assert "has ended" in preflight.lock_message(state, unlock)


def test_the_lock_message_offers_unlock_only_without_a_run_that_may_hold_it(tmp_path):
    state = locked_state(tmp_path)
    unlock = "stereovar run --configfile a.yaml -- --unlock"
    nobody = preflight.lock_message(state, unlock)
    assert "no record" in nobody and unlock in nobody and "wait" in nobody
    preflight.record_run(state, ended_process(), "stereovar audit a.yaml")
    ended = preflight.lock_message(state, unlock)
    assert "has ended" in ended and "run the same command again" in ended
    assert "--unlock" not in ended


def write_record(state: Path, host: str, pid: int, **fields) -> None:
    """A record of a Snakemake run as ``stereovar`` writes it as the run starts."""
    runs = state / preflight.RUNS_DIR
    runs.mkdir(exist_ok=True)
    (runs / f"{host}-{pid}.json").write_text(json.dumps({"host": host, "pid": pid, **fields}))


def test_a_lock_held_from_another_host_says_how_to_unlock_once_that_run_is_gone(tmp_path):
    state = locked_state(tmp_path)
    write_record(state, "node7", 4242, started=1.7e9, command="stereovar audit a.yaml")
    unlock = "stereovar run --configfile 'my a.yaml' -- --unlock"
    stamp = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(1.7e9))
    assert preflight.lock_message(state, unlock) == (
        f"{tmp_path} is locked by another run still going (pid 4242 on host node7, started "
        f"{stamp} (stereovar audit a.yaml)); wait for it to finish, then run the same command "
        "again; if no run is going on host node7 any more, remove the lock with "
        f"`{unlock}` and run the same command again"
    )


def test_a_live_pid_of_unknown_start_may_be_reused_and_says_how_to_unlock(tmp_path):
    state = locked_state(tmp_path)
    unlock = "stereovar run -- --unlock"
    with subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"]) as live:
        try:
            write_record(state, socket.gethostname(), live.pid)  # no start time: pid reused?
            unsure = preflight.lock_message(state, unlock)
            # its start time recorded: the same process, which may hold the lock
            preflight.record_run(state, live.pid, "stereovar audit a.yaml")
            sure = preflight.lock_message(state, unlock)
            write_record(state, "node7", 4242)  # and one elsewhere: still only wait
            both = preflight.lock_message(state, unlock)
        finally:
            live.kill()
    assert f"if pid {live.pid} is no longer a snakemake run in that folder, " in unsure
    assert f"`{unlock}`" in unsure
    for line in (sure, both):
        assert "wait for it to finish" in line and "--unlock" not in line, line


#: What Snakemake 9 prints when another run's lock covers this run's files.
LOCK_TAIL = """Building DAG of jobs...
LockException:
Error: Directory cannot be locked. Please make sure that no other Snakemake process is \
trying to create the same files in the following directory:
{root}
If you are sure that no other instances of snakemake are running on this directory, the \
remaining lock was likely caused by a kill signal or a power loss. It can be removed with \
the --unlock argument.
"""


def test_the_unlock_command_quotes_the_config_paths(tmp_path):
    locked_state(tmp_path)
    config = str(tmp_path / "my audit's.yaml")
    monitor = monitor_of(tmp_path, LOCK_TAIL.format(root=tmp_path).splitlines())
    monitor.configfiles = [config]
    (message,) = monitor.errors(1)
    assert "no record" in message, message
    unlock = message.split("remove the lock with `", 1)[1].split("`", 1)[0]
    assert shlex.split(unlock) == ["stereovar", "run", "--configfile", config, "--", "--unlock"]


def stand_in(monkeypatch, output: str, rc: int, before=None, failed=()) -> None:
    """Replace Snakemake with a process that prints ``output`` and exits with ``rc``, run
    through the audit's monitor as Snakemake is (recorded while it runs), and that reports
    the jobs ``failed`` as the logger plugin does (its summary file);
    ``before(root)`` first: what the workflow does before it stops."""
    script = (
        "import json, sys\n"
        f"sys.stdout.write({output!r})\n"
        "for arg in sys.argv:\n"
        "    if arg.startswith('--logger-stereovar-summary='):\n"
        "        with open(arg.split('=', 1)[1], 'w') as out:\n"
        f"            json.dump({{'failed': {list(failed)!r}}}, out)\n"
        f"sys.exit({rc})\n"
    )

    def run(args, root):
        if before is not None:
            before(root)
        return cli._MONITOR.get().run([sys.executable, "-c", script, *args], root)

    monkeypatch.setattr(cli, "_snakemake", run)


def ps_start(pid: int) -> float | None:
    """When process ``pid`` started, as ``ps`` tells it (seconds since the epoch)."""
    proc = subprocess.run(
        ["ps", "-o", "lstart=", "-p", str(pid)], capture_output=True, text=True,
        env={**os.environ, "LC_ALL": "C"},
    )
    try:
        return time.mktime(time.strptime(proc.stdout.strip(), "%a %b %d %H:%M:%S %Y"))
    except ValueError:
        return None


def test_a_second_audit_while_one_runs_names_it_and_waits(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    config = write_audit(tmp_path)
    state = locked_state(tmp_path)
    stand_in(monkeypatch, LOCK_TAIL.format(root=tmp_path), 1)
    before = time.time()
    with subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"]) as holder:
        after = time.time()
        try:
            preflight.record_run(state, holder.pid, "stereovar audit t.yaml")
            rc = cli.main(["audit", config, "--import-only"])
            started = ps_start(holder.pid)
        finally:
            holder.kill()
    err = capsys.readouterr().err
    assert rc != 0
    (line,) = [ln for ln in err.splitlines() if ln.startswith("stereovar: error:")]
    assert f"{tmp_path} is locked by another run still going (pid {holder.pid}, " in line
    stamp = line.split(", started ")[1][:19]
    shown = time.mktime(time.strptime(stamp, "%Y-%m-%d %H:%M:%S"))
    if started is not None:  # the same clock as ps, to the second
        assert abs(shown - started) <= 1, (stamp, started)
    else:
        assert before - 2 <= shown <= after + 1, (stamp, before, after)
    assert "(stereovar audit t.yaml)" in line and "wait for it to finish" in line
    assert "--unlock" not in err and "LockException" not in err
    # the record of the stand-in went with it; the holder's stays
    records = [p.name for p in (state / RUNS_DIR).iterdir()]
    assert records == [f"{socket.gethostname()}-{holder.pid}.json"]


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    """A one-frame audit imported once (``stereovar audit t.yaml --import-only``), the
    module's one real run, after an audit that was killed after it took its lock (on the
    import's record) and before its ``onstart``: only the record ``stereovar`` wrote as it
    started names that run. What the run left is read as it ends."""
    root = tmp_path_factory.mktemp("audit_errors")
    config = write_audit(root)
    state = root / ".snakemake"
    (state / "locks").mkdir(parents=True)
    (state / "locks" / "0.output.lock").write_text("results/audit/t/import/f00.json\n")
    preflight.record_run(state, ended_process(), "stereovar audit t.yaml")
    proc = audit(root, config, "--import-only")
    logs = sorted((root / "logs" / "audit" / "t").glob("stereovar-audit-*.log"))
    return SimpleNamespace(
        root=root,
        proc=proc,
        log=logs[-1].read_text() if logs else "",
        locks=sorted(p.name for p in (state / "locks").glob("*")),
        records=sorted(p.name for p in (state / RUNS_DIR).glob("*.json")),
    )


def audit(root, *args):
    return subprocess.run([sys.executable, "-m", "stereovar.cli", "audit", *args],
                          cwd=root, capture_output=True, text=True)


@pytest.mark.workflow
def test_the_next_audit_removes_the_lock_of_a_run_killed_before_onstart(imported):
    assert imported.proc.returncode == 0, imported.proc.stderr
    assert "stereovar: removed the lock of an earlier run that was killed" in imported.log
    # the killed run's record went once the new run held the lock, the new run's as it ended
    assert imported.locks == [] and imported.records == [], imported


# -- 2. cosmetic edits of the config rerun nothing ----------------------------------------------


def cosmetic(settings: dict) -> dict:
    """``settings`` with the keys (and views) reordered and defaults written out."""
    same = {key: settings[key] for key in reversed(list(settings))}
    same["views"] = dict(reversed(list(settings["views"].items())))
    same.update(scale=1.0, channels={}, disparity_scale=256, sign_check="stop")
    return same


def test_only_settings_the_import_applies_change_its_params(tmp_path):
    config = tmp_path / write_audit(tmp_path)
    settings = yaml.safe_load(config.read_text())["audit"]
    digest = audit_run.import_params(settings)
    # as the workflow sees them (the schema's defaults filled in), cosmetic edits, and
    # settings the import does not read: one digest
    assert audit_run.import_params(cli._workflow_config(tmp_path, [config])["audit"]) == digest
    assert audit_run.import_params(cosmetic(settings)) == digest
    assert audit_run.import_params({**settings, "mitigations": ["denoise"], "probe": True}) == (
        digest
    )
    swapped = {"left": settings["views"]["right"], "right": settings["views"]["left"]}
    for change in ({"scale": 2.0}, {"disparity_scale": 128}, {"views": swapped}):
        assert audit_run.import_params({**settings, **change}) != digest, change


@pytest.mark.workflow
def test_reordered_keys_and_written_defaults_import_nothing_again(imported, tmp_path):
    assert imported.proc.returncode == 0, imported.proc.stderr
    settings = yaml.safe_load((imported.root / "t.yaml").read_text())["audit"]
    same = tmp_path / "same.yaml"
    same.write_text(yaml.safe_dump({"audit": cosmetic(settings)}, sort_keys=False))
    proc = subprocess.run(
        [sys.executable, "-m", "snakemake", "--snakefile", str(REPO / "Snakefile"), "-n",
         "-j1", "--until", "audit_import", "--configfile", str(same)],
        cwd=imported.root, capture_output=True, text=True,
    )
    output = proc.stdout + proc.stderr
    assert proc.returncode == 0, output
    assert re.search(r"^total +0$", output, re.M) and "rule audit_import:" not in output, output


# -- 4. an import that cannot finish leaves no verdict on stores it replaced --------------------


def test_a_render_that_is_a_named_pipe_stops_before_snakemake(tmp_path, preflight_only):
    config = write_audit(tmp_path)
    settings = yaml.safe_load((tmp_path / config).read_text())["audit"]
    fifo = tmp_path / "data" / "renders" / "f00" / "R" / "seed_002.exr"
    fifo.unlink()
    os.mkfifo(fifo)
    line = one_error(*preflight_only(config))
    assert "data/renders/f00/R/seed_002.exr: not a regular file (a named pipe)" in line, line
    with pytest.raises(ImageError, match="named pipe"):
        audit_run.discover_audit(settings)


def test_setting_a_verdict_aside_moves_each_file_once(tmp_path):
    folder = tmp_path / "results" / "audit" / "t"
    (folder / PREVIOUS).mkdir(parents=True)
    (folder / PREVIOUS / "verdict.html").write_text("older")
    for name in ("verdict.md", "verdict.html", "summary.json"):
        (folder / name).write_text(f"red {name}")
    moved = audit_run.set_aside_verdict("t", tmp_path)
    assert sorted(p.name for p in moved) == ["summary.json", "verdict.html", "verdict.md"]
    assert not any((folder / n).exists() for n in ("verdict.md", "verdict.html", "summary.json"))
    assert (folder / PREVIOUS / "verdict.html").read_text() == "red verdict.html"
    assert audit_run.set_aside_verdict("t", tmp_path) == []


#: What Snakemake 9 prints when the import job of frame f00 fails.
FAILED_IMPORT = """Error in rule audit_import:
    message: None
    jobid: 1
    output: results/audit/t/import/f00.json
    log: logs/audit/t/import/f00.log (check log file(s) for error details)
Shutting down, this might take some time.
Exiting because a job execution failed. Look below for error messages
"""


def test_a_failed_import_says_where_the_old_verdict_went(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    config = write_audit(tmp_path)
    folder = tmp_path / "results" / "audit" / "t"
    folder.mkdir(parents=True)
    verdict = {"verdict.html": "<p>RED</p>", "summary.json": json.dumps({"summary": ["RED"]})}
    for name, text in verdict.items():
        (folder / name).write_text(text)
    log = Path("logs/audit/t/import/f00.log")
    error = "data/renders/f00/L/seed_001.exr: the file is truncated"

    def onstart(root):  # the workflow sets the verdict aside, then the import job fails
        audit_run.set_aside_verdict("t", root)
        log.parent.mkdir(parents=True, exist_ok=True)
        log.write_text(f"2026-01-01 00:00:00 ERROR error: {error}\n")

    failed = [{"rule": "audit_import", "jobid": 1, "logs": [str(log)]}]
    stand_in(monkeypatch, FAILED_IMPORT, 1, before=onstart, failed=failed)
    rc = cli.main(["audit", config, "--import-only"])
    err = capsys.readouterr().err.splitlines()
    assert rc != 0
    assert [ln for ln in err if ln.startswith("stereovar: error:")] == [
        f"stereovar: error: {error}"
    ]
    assert f"the verdict before this run, set aside as out of date: {folder / PREVIOUS}/" in err
    assert err[-1].startswith("log: ") and err[-1].endswith(f"(the failed job's: {log})")
    for name, text in verdict.items():
        assert not (folder / name).exists() and (folder / PREVIOUS / name).read_text() == text


# -- 5. the rebuild advice works for an installed stereovar --------------------------------------


def test_the_rebuild_command_is_a_stereovar_run_that_forces_the_one_store(
    tmp_path, monkeypatch
):
    (tmp_path / "my config.yaml").write_text("{}\n")
    store = "results/audit/t/renders/f00/left/spp0/seeds0-3.zarr"
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv(
        RERUN_ARGS_ENV, "--configfile 'my config.yaml' --config 'render={spp: 4}'"
    )
    command = shlex.split(rebuild_command(store))
    assert command[:2] == ["stereovar", "run"]
    started = []
    monkeypatch.setattr(cli, "_snakemake", lambda args, root: started.append(args) or 0)
    assert cli.main(command[1:]) == 0
    assert started == [
        ["-j", "1", store, "--configfile", "my config.yaml", "--force", "--config",
         "render={spp: 4}"]
    ]
    monkeypatch.delenv(RERUN_ARGS_ENV)
    assert rebuild_command(store).startswith(
        "stereovar run -j1 --configfile <the config of the run that made it> "
    )
