"""The workflow on a real single-node SLURM cluster (scripts/slurm_local.sh) via profiles/slurm.

The cluster (munge, MariaDB, slurmdbd, slurmctld, slurmd) is started for this module and
stopped by process id at its end. Where it cannot be provided (not root, no apt-get, or a
munged already serving the standard socket) every test here is skipped with the script's
reason, which pytest's summary (``-ra``) prints.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .test_workflow import SCENES, TINY, copy_workflow

REPO = Path(__file__).resolve().parents[1]
SCRIPT = REPO / "scripts/slurm_local.sh"
#: Status checks every 2 s instead of the profile's cluster-friendly 30 s.
FAST = ["--slurm-init-seconds-before-status-checks", "1", "--seconds-between-status-checks", "2"]

#: One cluster for the module, beside the local run it is compared with: every test here stays
#: on the shared tiny run's xdist worker (tests/conftest.py).
pytestmark = [pytest.mark.slurm, pytest.mark.workflow, pytest.mark.xdist_group("tiny_run")]


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """Environment of a running local cluster (SLURM_CONF set)."""
    state = tmp_path_factory.mktemp("slurm-state")
    env = {**os.environ, "STEREOVAR_SLURM_DIR": str(state)}
    proc = subprocess.run(["bash", str(SCRIPT), "start"], env=env, capture_output=True, text=True)
    if proc.returncode == 3:
        pytest.skip(f"no local SLURM cluster on this machine: {proc.stderr.strip()}")
    if proc.returncode != 0:
        logs = "\n".join(
            f"--- {p.name}\n{p.read_text()[-2000:]}" for p in sorted((state / "log").glob("*"))
        )
        subprocess.run(["bash", str(SCRIPT), "stop"], env=env, capture_output=True)
        pytest.fail(f"slurm_local.sh start failed: {proc.stderr}\n{logs}")
    env["SLURM_CONF"] = str(state / "slurm.conf")
    daemons = dict(line.split() for line in (state / "pids").read_text().splitlines())
    assert set(daemons) == {"munged", "mariadbd", "slurmdbd", "slurmctld", "slurmd"}
    yield env
    stop = subprocess.run(["bash", str(SCRIPT), "stop"], env=env, capture_output=True, text=True)
    assert stop.returncode == 0, stop.stderr
    assert not (state / "pids").exists(), "the stop left the pid file behind"
    alive = [name for name, pid in daemons.items() if running(int(pid))]
    assert not alive, f"still running after stop: {alive}"
    # no copy of this cluster's config is left for later SLURM clients to wait on
    cached = Path("/run/slurm/conf/slurm.conf")
    assert not (cached.is_file() and "ClusterName=stereovar" in cached.read_text())


def running(pid: int) -> bool:
    """Whether a process exists and is not a zombie waiting to be reaped."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def snakemake_cmd(*args):
    return [sys.executable, "-m", "snakemake", *args, "--configfile", "tiny.yaml"]


def run(workdir, env, *args, check=True):
    proc = subprocess.run(
        snakemake_cmd(*args), cwd=workdir, env=env, capture_output=True, text=True, timeout=1200
    )
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{proc.stdout}\n{proc.stderr}")
    return proc


def sacct(env, workdir) -> list[dict]:
    """This workflow's SLURM jobs (allocations only) from the accounting database."""
    out = subprocess.run(
        ["sacct", "-X", "-P", "-n", "-S", "now-6hours", "-a",
         "--format", "JobID,State,WorkDir,Comment"],
        env=env, capture_output=True, text=True, check=True,
    ).stdout  # fmt: skip
    jobs = []
    for line in out.splitlines():
        job_id, state, work, comment = line.split("|", 3)
        if Path(work) == Path(workdir):
            jobs.append({"id": int(job_id), "state": state.split()[0], "comment": comment})
    return jobs


#: What the kill tests build: every render job (both scenes at the main SPP and the sweep's
#: other SPP) and the chain after it up to the correlation rows, which equal the local run's
#: only when every render does; the tables, figures and interventions of ``all`` add nothing
#: to what a killed render job tests.
RENDERED = [
    f"results/mitsuba/seeds/correlation/{scene}/spp{spp}.csv"
    for scene, spp in (("scene_000", 1), ("scene_000", 2), ("scene_001", 2))
]


def outputs(workdir) -> dict:
    """Every table and per-scene CSV, as bytes."""
    root = Path(workdir) / "results"
    files = [
        *root.glob("tables/*"),
        *root.glob("*/*/tables/*"),
        *root.glob("*/*/correlation/*/*.csv"),
        *root.glob("*/*/intervention/**/*.csv"),
    ]
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(files)}


@pytest.fixture(scope="module")
def local_reference(tiny_run):
    """The tiny config run locally with -j2."""
    return tiny_run


@pytest.fixture(scope="module")
def slurm_run(cluster, tmp_path_factory):
    workdir = copy_workflow(tmp_path_factory.mktemp("slurm") / "wf", TINY)
    start = time.perf_counter()
    run(workdir, cluster, "--profile", "profiles/slurm", "all", *FAST)
    return workdir, time.perf_counter() - start


def test_slurm_tables_equal_the_local_run_bit_for_bit(slurm_run, local_reference):
    workdir, _ = slurm_run
    cluster_out, local_out = outputs(workdir), outputs(local_reference)
    assert len(local_out) >= 15
    assert cluster_out.keys() == local_out.keys()
    for name, data in local_out.items():
        assert cluster_out[name] == data, f"{name} differs between SLURM and local runs"


def test_jobs_went_through_sbatch_and_are_accounted(slurm_run, cluster):
    workdir, _ = slurm_run
    jobs = sacct(cluster, workdir)
    assert jobs and all(j["state"] == "COMPLETED" for j in jobs)
    comments = [j["comment"] for j in jobs]
    # Render batches: 2 scenes at the main SPP + the sweep scene at its other SPP.
    assert sum(c.startswith("rule_render_") for c in comments) == 3, comments
    assert sum("intervention" in c for c in comments) == len(SCENES)
    # Local rules (tables, figures) never reach SLURM.
    assert not any("table" in c or "figure" in c for c in comments)


def wait_for_running_render(env, workdir, proc, timeout=600):
    """Job id of a render job of this workflow once SLURM runs it."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        assert proc.poll() is None, "the workflow ended before a render job ran"
        out = subprocess.run(
            ["squeue", "-h", "-t", "RUNNING", "-o", "%i|%Z|%k"],
            env=env, capture_output=True, text=True,
        ).stdout  # fmt: skip
        for line in out.splitlines():
            job_id, work, comment = line.split("|", 2)
            if Path(work) == Path(workdir) and comment.startswith("rule_render"):
                return int(job_id), comment
        time.sleep(0.2)
    raise AssertionError("no render job ran within the timeout")


def _parent(pid: int) -> int | None:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return int(stat.rsplit(")", 1)[1].split()[1])


def _comm(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/comm").read_text().strip()
    except OSError:
        return ""


def job_step_pids(listed, protected) -> list[int]:
    """Of the pids ``scontrol listpids`` gave, those that run under one of the job's
    ``slurmstepd`` processes and are none of ``protected`` (the workflow and this test, with
    their ancestors).

    ``proctrack/linuxproc`` collects a job's processes by walking /proc, and on some machines
    its list reaches past the job: the workflow that submitted it was killed with the job.
    Only descendants of a ``slurmstepd`` are the job's own step processes.
    """
    keep = []
    for pid in listed:
        if pid in protected:
            continue
        parent = _parent(pid)
        while parent not in (None, 0, 1) and _comm(parent) != "slurmstepd":
            parent = _parent(parent)
        if parent not in (None, 0, 1):
            keep.append(pid)
    return keep


def lineage(pid: int) -> set[int]:
    """``pid`` and its ancestors."""
    out = set()
    while pid not in (None, 0) and pid not in out:
        out.add(pid)
        pid = _parent(pid)
    return out


def kill_job_processes(env, job_id, workflow_pid):
    """SIGKILL the step processes of a running SLURM job, as an OOM killer or a crash would
    (:func:`job_step_pids`: never the workflow's process or this test's).

    (``scancel`` is not used: sacct then reports the state as ``CANCELLED by <uid>``, which
    snakemake-executor-plugin-slurm 2.8 does not recognise, so the workflow would wait on
    the job forever.)
    """
    protected = lineage(os.getpid()) | lineage(workflow_pid)
    deadline = time.time() + 60
    while time.time() < deadline:
        out = subprocess.run(
            ["scontrol", "listpids", str(job_id)], env=env, capture_output=True, text=True
        ).stdout
        listed = [int(line.split()[0]) for line in out.splitlines()[1:] if line.split()]
        pids = job_step_pids(listed, protected)
        if pids:
            for pid in pids:
                try:
                    os.kill(pid, 9)
                except ProcessLookupError:
                    pass
            return
        time.sleep(0.2)
    raise AssertionError(f"no step process of SLURM job {job_id} found")


def kill_one_render(env, workdir, *args):
    """Start the workflow on SLURM for :data:`RENDERED`, kill the first render job that
    runs, wait for the end."""
    proc = subprocess.Popen(
        snakemake_cmd("--profile", "profiles/slurm", *RENDERED, *FAST, *args),
        cwd=workdir, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    job_id, comment = wait_for_running_render(env, workdir, proc)
    kill_job_processes(env, job_id, proc.pid)
    output, _ = proc.communicate(timeout=1200)
    return proc.returncode, output, job_id, comment


def render_submissions(env, workdir) -> dict:
    counts: dict = {}
    for job in sacct(env, workdir):
        if job["comment"].startswith("rule_render"):
            counts.setdefault(job["comment"], []).append(job["state"])
    return counts


def rendered_outputs(workdir, local_reference) -> tuple[dict, dict]:
    """The correlation rows of :data:`RENDERED` (with their curves) in ``workdir`` and in
    the local run."""
    built, local = outputs(workdir), outputs(local_reference)
    stems = [str(Path(p).relative_to("results")).removesuffix(".csv") for p in RENDERED]
    names = {n for n in local if any(n in (f"{s}.csv", f"{s}_curve.csv") for s in stems)}
    assert len(names) == 2 * len(RENDERED) and set(built) == names, sorted(built)
    return built, {name: local[name] for name in names}


def test_killed_render_is_retried_and_nothing_finished_is_rerendered(
    cluster, tmp_path_factory, local_reference
):
    workdir = copy_workflow(tmp_path_factory.mktemp("retry") / "wf", TINY)
    rc, output, job_id, comment = kill_one_render(cluster, workdir)
    assert rc == 0, output[-4000:]
    submissions = render_submissions(cluster, workdir)
    assert submissions[comment] == ["FAILED", "COMPLETED"]  # the profile's retries
    assert all(states == ["COMPLETED"] for c, states in submissions.items() if c != comment)
    assert len(submissions) == 3
    built, local = rendered_outputs(workdir, local_reference)
    assert built == local
    assert not list((workdir / "results").rglob(".*tmp-*"))


def test_failed_run_is_reported_and_a_rerun_completes_only_what_is_missing(
    cluster, tmp_path_factory, local_reference
):
    workdir = copy_workflow(tmp_path_factory.mktemp("resume") / "wf", TINY)
    rc, output, job_id, comment = kill_one_render(cluster, workdir, "--retries", "0")
    assert rc != 0 and "Error in rule render:" in output
    before = render_submissions(cluster, workdir)
    assert before[comment] == ["FAILED"]
    finished = {c for c, states in before.items() if states == ["COMPLETED"]}
    run(workdir, cluster, "--profile", "profiles/slurm", *RENDERED, *FAST)
    after = render_submissions(cluster, workdir)
    assert after[comment] == ["FAILED", "COMPLETED"]
    for done in finished:
        assert after[done] == ["COMPLETED"], f"{done} was rendered again"
    built, local = rendered_outputs(workdir, local_reference)
    assert built == local
    assert not list((workdir / "results").rglob(".*tmp-*"))


def test_only_a_job_steps_own_processes_are_killed(tmp_path):
    """Of a pid list reaching past the job (this test, its parents, init), only the child of
    a ``slurmstepd`` is a step process (a copy of bash named slurmstepd stands in for it)."""
    import shutil as sh

    stepd = tmp_path / "slurmstepd"
    sh.copy("/bin/bash", stepd)
    parent = subprocess.Popen([str(stepd), "-c", "sleep 60 & wait"])
    children: list[int] = []
    try:
        deadline = time.time() + 10
        while not children and time.time() < deadline:
            children = [
                int(p.name)
                for p in Path("/proc").iterdir()
                if p.name.isdigit() and _parent(int(p.name)) == parent.pid
            ]
            time.sleep(0.05)
        assert children and _comm(parent.pid) == "slurmstepd"
        protected = lineage(os.getpid())
        listed = [1, os.getpid(), *protected, parent.pid, *children]
        assert job_step_pids(listed, protected) == children
    finally:
        for pid in children:
            try:
                os.kill(pid, 9)
            except ProcessLookupError:
                pass
        parent.kill()
        parent.wait()
