"""A run no second run can disturb, and the commands' guards before any work.

- Each of ``stereovar run``, ``audit``, ``probe`` and ``export`` holds a lock over the results
  it may write (:mod:`stereovar.run_lock`) for its whole run: a second command that would
  write them is refused in one line naming the holder; commands over disjoint results (two
  audits of different names) run side by side. One test runs real audits so: two audits
  overlap in one folder, the first stopped while its Snakemake holds its locks, the second
  ends (and Snakemake removes every lock of the folder), a third run of the first audit is
  refused, and both audits' results equal those of clean runs.
- ``-j`` below 1 is refused by every command, from one place.
- ``--fail-on`` reads ``summary.json`` through its schema and fails closed.
- Ctrl-C is said as such, with exit status 130.
- A user's paths are printed with control characters escaped.
- Killed runs' summaries in the temporary folder are removed by the next run.

Most tests call the command with Snakemake replaced (a stub that fails the test if started,
or a stand-in process run through the command's monitor).
"""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from stereovar import cli
from stereovar.audit.importer import import_audit as library_import
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.cli import monitor
from stereovar.layout import run_lock
from stereovar.preflight import process_start
from stereovar.run_lock import RunLock

from .test_audit_cli_errors import stand_in, write_audit

#: A process that takes the lock of SCOPE in ROOT with COMMAND recorded, says so, and holds
#: it until killed.
HOLDER = """import sys, time
from stereovar.run_lock import RunLock
with RunLock(sys.argv[1], sys.argv[2], sys.argv[3]):
    print("held", flush=True)
    time.sleep(120)
"""


@pytest.fixture
def holder(tmp_path):
    """``hold(scope, command)``: a process holding ``scope``'s lock in ``tmp_path``."""
    procs = []

    def hold(scope, command="stereovar audit other.yaml"):
        proc = subprocess.Popen([sys.executable, "-c", HOLDER, str(tmp_path), scope, command],
                                stdout=subprocess.PIPE, text=True)
        procs.append(proc)
        assert proc.stdout.readline() == "held\n"
        return proc

    yield hold
    for proc in procs:
        proc.kill()
        proc.wait()


@pytest.fixture
def no_snakemake(tmp_path, monkeypatch):
    """Work in ``tmp_path`` with Snakemake replaced by a stub that fails the test."""

    def never(args, root):
        raise AssertionError(f"snakemake started: {args}")

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(cli, "_snakemake", never)


def error_line(capsys) -> str:
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("stereovar: error: "), err
    return err[0]


# -- 1. the run lock --------------------------------------------------------------------------


def test_an_audit_whose_results_another_run_writes_is_refused_naming_it(
    tmp_path, no_snakemake, holder, capsys
):
    config = write_audit(tmp_path)
    before = time.time()
    proc = holder("audit-t", "stereovar audit t.yaml -j1")
    written = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    assert cli.main(["audit", config]) == 2
    line = error_line(capsys)
    assert f"the audit t's results ({tmp_path}/results/audit/t) are being written" in line
    assert f"(pid {proc.pid}, started " in line and "(stereovar audit t.yaml -j1)" in line
    stamp = line.split(", started ")[1][:19]
    started = process_start(proc.pid) or before
    assert abs(time.mktime(time.strptime(stamp, "%Y-%m-%d %H:%M:%S")) - started) <= 1.5
    assert "wait for it to finish, then run the same command again" in line
    # refused before anything was written: no log, no record
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == written


def test_an_audit_of_another_name_runs_beside_it_and_the_lock_goes_with_its_holder(
    tmp_path, monkeypatch, holder, capsys
):
    monkeypatch.chdir(tmp_path)
    config = write_audit(tmp_path)
    stand_in(monkeypatch, "", 0)
    proc = holder("audit-other")
    assert cli.main(["audit", config, "--import-only"]) == 0, capsys.readouterr().err
    assert capsys.readouterr().out.startswith("imported t: ")
    proc = holder("audit-t")
    assert cli.main(["audit", config, "--import-only"]) == 2
    assert f"(pid {proc.pid}, " in capsys.readouterr().err
    proc.kill()  # killed: the kernel frees its lock, nothing to remove
    proc.wait()
    assert cli.main(["audit", config, "--import-only"]) == 0
    assert (tmp_path / run_lock("audit-t")).read_text() == ""  # no holder named once free


@pytest.mark.parametrize("command", [["run"], ["run", "--", "--unlock"],
                                     ["export", "--format", "npy"]])
def test_run_and_export_are_refused_while_a_run_writes_the_results(
    tmp_path, no_snakemake, holder, capsys, command
):
    proc = holder("run", "stereovar run -j2")
    assert cli.main(command) == 2
    line = error_line(capsys)
    assert f"the workflow's results ({tmp_path}/results, the audits' aside)" in line
    assert f"(pid {proc.pid}, " in line and "(stereovar run -j2)" in line


def test_a_dry_run_writes_nothing_and_takes_no_lock(tmp_path, monkeypatch, holder, capsys):
    monkeypatch.chdir(tmp_path)
    ran = []
    monkeypatch.setattr(cli, "_snakemake", lambda args, root: ran.append(args) or 0)
    holder("run")
    assert cli.main(["run", "--", "-n"]) == 0 and ran


def test_the_lock_is_held_for_the_whole_command(tmp_path, monkeypatch, capsys):
    """While Snakemake runs (here a stand-in that looks), the command holds its scope."""
    monkeypatch.chdir(tmp_path)
    seen = []

    def look(args, root):
        try:
            with RunLock(root, "run", "probe"):
                seen.append("free")
        except cli.StereovarError as err:
            seen.append(str(err))
        return 0

    monkeypatch.setattr(cli, "_snakemake", look)
    assert cli.main(["run", "-j1"]) == 0
    assert len(seen) == 1 and "are being written by another stereovar run (pid " in seen[0]
    assert f"pid {os.getpid()}, " in seen[0] and "(stereovar run -j1)" in seen[0]


def import_audit(root: Path, name: str, data: str) -> str:
    """A one-frame synthetic audit ``name`` (40 x 24, 4 seeds a view) with its files under
    ``root/data``; returns its config's file name."""
    settings, _ = write_synthetic_audit(root / data, name=name, n_frames=1, width=40,
                                        height=24, n_seeds=4)
    settings["renders"] = f"{data}/renders/{{frame}}/{{view}}/seed_{{seed}}.exr"
    settings["disparity"] = f"{data}/disparity/{{frame}}.pfm"
    (root / f"{name}.yaml").write_text(yaml.safe_dump({"audit": settings}))
    return f"{name}.yaml"


def audit_cmd(root, *args, **kw):
    return subprocess.Popen([sys.executable, "-m", "stereovar.cli", "audit", *args, "-j1"],
                            cwd=root, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, **kw)


def results_of(root: Path, name: str) -> dict:
    """What an import wrote, by meaning: each store's variables and the records' fields that
    do not name the folder or the time."""
    out = {}
    folder = root / "results" / "audit" / name
    for store in sorted(folder.rglob("*.zarr")):
        with xr.open_zarr(store) as ds:
            for var in ds.data_vars:
                out[f"{store.relative_to(folder)}:{var}"] = np.asarray(ds[var].values)
    for path in sorted((folder / "import").glob("*.json")):
        out[str(path.relative_to(folder))] = by_meaning(json.loads(path.read_text()), root)
    return out


def by_meaning(value, root: Path):
    """A record without what tells one copy of the same files from another: file times,
    inodes and the change token made of them, and strings that name the folder."""
    if isinstance(value, dict):
        return {k: by_meaning(v, root) for k, v in value.items()
                if k not in ("ino", "dev", "token") and "time" not in k}
    if isinstance(value, list):
        return [by_meaning(v, root) for v in value]
    return "<root>" if isinstance(value, str) and str(root) in value else value


def assert_same(got: dict, want: dict) -> None:
    assert sorted(got) == sorted(want) and got
    for key, value in want.items():
        if isinstance(value, np.ndarray):
            np.testing.assert_array_equal(got[key], value, err_msg=key)
        else:
            assert got[key] == value, key


@pytest.mark.workflow
def test_overlapping_audits_in_one_folder_keep_their_results(tmp_path, monkeypatch):
    shared = tmp_path / "shared"
    shared.mkdir()
    configs = {n: import_audit(shared, n, f"data_{n}") for n in "ab"}
    clean = {}
    for n in "ab":  # each imported alone in a folder of its own, as its import job does
        root = tmp_path / f"clean_{n}"
        root.mkdir()
        import_audit(root, n, f"data_{n}")
        monkeypatch.chdir(root)
        settings = yaml.safe_load((root / configs[n]).read_text())["audit"]
        assert [f.name for f in library_import(settings).frames] == ["f00"]
        clean[n] = results_of(root, n)

    first = audit_cmd(shared, configs["a"], "--import-only", start_new_session=True)
    locks = shared / ".snakemake" / "locks"
    deadline = time.time() + 60
    while not (locks.is_dir() and any(locks.iterdir())):  # its Snakemake holds its locks
        assert first.poll() is None and time.time() < deadline, first.communicate()
        time.sleep(0.005)
    os.killpg(first.pid, signal.SIGSTOP)
    try:
        second = audit_cmd(shared, configs["b"], "--import-only")
        assert second.wait() == 0, second.stderr.read()
        # Snakemake removed the locks of every run in the folder as the second one ended
        assert not (locks.is_dir() and any(locks.iterdir()))
        third = audit_cmd(shared, configs["a"], "--import-only")
        assert third.wait() == 2
        (line,) = third.stderr.read().splitlines()
        assert "the audit a's results" in line and f"(pid {first.pid}, " in line, line
        assert "(stereovar audit a.yaml --import-only -j1)" in line
    finally:
        os.killpg(first.pid, signal.SIGCONT)
    out, err = first.communicate(timeout=120)
    assert first.returncode == 0, err
    assert_same(results_of(shared, "a"), clean["a"])
    assert_same(results_of(shared, "b"), clean["b"])


# -- 2. -j below 1, from one place ------------------------------------------------------------


@pytest.mark.parametrize("cores", ["0", "-3"])
@pytest.mark.parametrize("command", ["run", "audit", "export", "probe"])
def test_every_command_refuses_fewer_than_one_core(tmp_path, no_snakemake, capsys, command,
                                                   cores):
    args = {
        "run": ["run"],
        "audit": ["audit", write_audit(tmp_path)],
        "export": ["export", "--format", "npy"],
        "probe": ["probe", "--model", "m:f", "--weights", "w.pt"],
    }[command]
    assert cli.main([*args, "-j", cores]) == 2
    line = error_line(capsys)
    assert line == (
        f"stereovar: error: -j {cores}: a run needs at least 1 core; give -j 1 or more (e.g. -j 2)"
    )


# -- 3. the gate reads summary.json through its schema ----------------------------------------


@pytest.mark.parametrize(
    "text, why",
    [
        ("{not json", "it is not JSON"),
        ('["green"]', "it holds a JSON list, not an object"),
        ('{"light": "green", "summary": "GREEN: a string"}', "breaks its schema"),
    ],
)
def test_the_gate_fails_closed_on_a_summary_it_cannot_read(tmp_path, monkeypatch, capsys, text,
                                                           why):
    monkeypatch.chdir(tmp_path)
    config = write_audit(tmp_path)
    summary = tmp_path / "results" / "audit" / "t" / "summary.json"

    def write(root):
        summary.parent.mkdir(parents=True, exist_ok=True)
        summary.write_text(text)

    stand_in(monkeypatch, "", 0, before=write)
    assert cli.main(["audit", config, "--fail-on", "amber"]) == 2
    line = error_line(capsys)
    assert f"{summary.relative_to(tmp_path)} is not a summary the verdict job wrote" in line
    assert why in line and "remove it and run the same stereovar audit command again" in line


# -- 4. Ctrl-C --------------------------------------------------------------------------------


@pytest.mark.parametrize("host", ["python", "its own handler"])
def test_ctrl_c_is_said_as_an_interruption_with_status_130(tmp_path, monkeypatch, capsys, host,
                                                           request):
    """Snakemake (a stand-in) reports its running jobs failed as it stops on SIGINT; the
    command says the run was interrupted and exits 130, also in a process whose SIGINT
    handler is not Python's (a host that embeds the command, or a library run before it in
    the same process), and gives that handler back."""
    import signal

    previous = signal.getsignal(signal.SIGINT)
    request.addfinalizer(lambda: signal.signal(signal.SIGINT, previous))
    if host != "python":
        signal.signal(signal.SIGINT, lambda *_: None)
    mine = signal.getsignal(signal.SIGINT)
    monkeypatch.chdir(tmp_path)
    config = write_audit(tmp_path)
    script = (
        "import json, os, signal, sys, time\n"
        "summary = [a.split('=', 1)[1] for a in sys.argv if a.startswith('--logger-stereovar-"
        "summary=')][0]\n"
        "def stop(*_):\n"
        "    json.dump({'failed': [{'rule': 'calibration_scene', 'jobid': 3, 'logs': ['c.log']},"
        " {'rule': 'audit_teaser', 'jobid': 4, 'logs': ['t.log']}]}, open(summary, 'w'))\n"
        "    sys.exit(1)\n"
        "signal.signal(signal.SIGINT, stop)\n"
        "time.sleep(0.5)\n"
        "os.kill(os.getppid(), signal.SIGINT)\n"  # the terminal's Ctrl-C reaches both
        "os.kill(os.getpid(), signal.SIGINT)\n"
        "time.sleep(30)\n"
    )
    monkeypatch.setattr(
        cli, "_snakemake",
        lambda args, root: cli._MONITOR.get().run([sys.executable, "-c", script, *args], root),
    )
    assert cli.main(["audit", config]) == monitor.INTERRUPTED_STATUS
    err = capsys.readouterr().err
    assert f"stereovar: error: {monitor.INTERRUPTED}" in err.splitlines()
    assert "failed" not in err and "c.log" not in err  # stopped, not failed
    assert err.splitlines()[-1].startswith("log: logs/audit/t/")
    assert signal.getsignal(signal.SIGINT) is mine


# -- 5. control characters, stale summaries ---------------------------------------------------


def test_a_users_path_is_printed_with_its_control_characters_escaped(tmp_path, no_snakemake,
                                                                     capsys):
    evil = "e\x1b]0;TITLE\x07\x1b[2K"
    assert cli.main(["audit", f"{evil}/a.yaml"]) == 2
    line = error_line(capsys)
    assert "\x1b" not in line and "\x07" not in line
    assert "e\\x1b]0;TITLE\\x07\\x1b[2K/a.yaml: no such config file" in line


def test_the_summaries_of_killed_runs_are_removed_by_the_next(tmp_path, monkeypatch):
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    killed = tmp_path / f"{monitor.SUMMARY_PREFIX}{gone}-x1y2.json"
    mine = tmp_path / f"{monitor.SUMMARY_PREFIX}{os.getpid()}-a8b9.json"
    old = tmp_path / f"{monitor.SUMMARY_PREFIX}q3z_k2m1.json"  # an older stereovar's
    recent = tmp_path / f"{monitor.SUMMARY_PREFIX}w2e4r6t8.json"
    for path in (killed, mine, old, recent):
        path.write_text("")
    os.utime(old, (time.time() - 2 * 86400,) * 2)
    log = tmp_path / "run.log"
    log.write_text("")
    run = cli._Run(log)
    assert run.run([sys.executable, "-c", "pass"], tmp_path) == 0
    left = sorted(p.name for p in tmp_path.glob(f"{monitor.SUMMARY_PREFIX}*.json"))
    assert left == sorted([mine.name, recent.name])


# -- 6. config and plan --------------------------------------------------------------------------


def test_a_refused_config_stops_a_dry_run_before_snakemake(tmp_path, no_snakemake, capsys):
    (tmp_path / "config.yaml").write_text("render:\n  spp: 0\n")
    assert cli.main(["run", "--", "-n"]) == 2
    line = error_line(capsys)
    assert "config key 'render.spp': 0 is too small" in line
    assert "Nothing to be done" not in line


def test_a_dry_run_that_stopped_before_its_plan_claims_nothing():
    from stereovar.progress import RUN_STAGES, Progress

    assert Progress(RUN_STAGES).plan_lines() == ""  # the workflow's own error says why
    nothing = Progress(RUN_STAGES)
    nothing.nothing = True
    assert nothing.plan_lines() == "Nothing to be done: every result is up to date\n"


def test_equal_views_are_refused_in_one_line(tmp_path, no_snakemake, capsys):
    config = write_audit(tmp_path)
    data = yaml.safe_load((tmp_path / config).read_text())
    data["audit"]["views"] = {"left": "L", "right": "L"}
    (tmp_path / config).write_text(yaml.safe_dump(data))
    assert cli.main(["audit", config]) == 2
    assert error_line(capsys) == (
        "stereovar: error: audit.views gives both views the value 'L', so no file can be told "
        "to be the left or the right view; give each its own {view} value (e.g. views: "
        "{left: L, right: R})"
    )


def test_asking_for_one_render_per_view_gets_the_measured_refusal(tmp_path, no_snakemake,
                                                                  capsys):
    from stereovar.estimators.single import refusal

    config = write_audit(tmp_path, single_render=True)
    assert cli.main(["audit", config]) == 2
    assert error_line(capsys) == (
        f"stereovar: error: config key 'audit.single_render': {refusal()}"
    )


def test_a_results_folder_that_cannot_be_written_is_said_before_the_lock(tmp_path):
    from .test_config_limits import read_only

    (tmp_path / "results").mkdir()
    prefix = read_only(tmp_path / "results")
    script = ("import sys; from stereovar import cli; "
              "cli._snakemake = lambda a, r: sys.exit('snakemake started'); "
              "sys.exit(cli.main(['run']))")
    proc = subprocess.run([*prefix, sys.executable, "-c", script], cwd=tmp_path,
                          capture_output=True, text=True)
    assert proc.returncode == 2, proc.stderr
    (line,) = proc.stderr.splitlines()
    assert line.startswith(f"stereovar: error: {tmp_path / 'results'} is on a read-only file "
                           "system and this run writes there") or (
        os.geteuid() != 0 and "is not writable by this user" in line), line
