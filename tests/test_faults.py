"""Fault injection: no completed render is lost, bad inputs stop before any job starts, damaged
stores name the one command that rebuilds them, and a killed run resumes with the same command.

Each test runs the real workflow on a copy with two tiny scenes (``tests/test_workflow.py``)."""

import hashlib
import os
import re
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from stereovar.io.store import open_dataset

from .test_workflow import REPO, RUN, TINY, copy_workflow, planned_jobs, snakemake

pytestmark = pytest.mark.workflow

FAULT = {**TINY, "render": {**TINY["render"], "spp_sweep": {"scene": "scene_000", "spp": [2]}}}
RENDERS = "results/mitsuba/renders"


def listing(root: Path) -> dict:
    """SHA-256 of every file under ``results/``, by path."""
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted((root / "results").rglob("*"))
        if p.is_file()
    }


def render_counts(root: Path, scene: str, spp: int = 2) -> tuple[int, int]:
    """(rendered, read from the cache) in the last render job of a scene's batch."""
    text = (root / f"logs/mitsuba/renders/{scene}/spp{spp}/seeds0-1.log").read_text()
    m = re.search(r"(\d+) of (\d+) renders rendered, (\d+) from the render cache", text)
    assert m, text
    return int(m.group(1)), int(m.group(3))


def radiance(root: Path, scene: str) -> np.ndarray:
    return np.stack(
        [
            open_dataset(root / f"{RENDERS}/{scene}/{v}/spp2/seeds0-1.zarr")["radiance"].values
            for v in ("left", "right")
        ]
    )


def stopped_with(proc, needle: str) -> str:
    """The run failed before any job with one ``stereovar:`` line containing ``needle``."""
    text = proc.stdout + proc.stderr
    assert proc.returncode != 0, text
    assert "Traceback" not in text, text
    assert not re.search(r"^rule \w+:", proc.stdout, flags=re.M), text
    lines = [ln for ln in text.splitlines() if ln.startswith("stereovar:")]
    assert len(lines) == 1 and needle in lines[0], text
    return lines[0]


def rerender_all(root: Path, **kwargs):
    """``snakemake -j2 all --forcerun render``, expected to fail."""
    return snakemake(root, "-j2", "all", "--forcerun", "render", check=False, **kwargs)


@pytest.fixture(scope="module")
def done(tiny_run_copy, tmp_path_factory):
    """A finished tiny run (a copy of the shared one: these tests damage it)."""
    return tiny_run_copy(tmp_path_factory.mktemp("faults") / "wf")


def test_unavailable_variant_stops_before_any_job_and_keeps_every_result(done):
    before = listing(done)
    proc = rerender_all(
        done, config={"render": {"variant": "cuda_ad_rgb"}}, env={"CUDA_VISIBLE_DEVICES": ""}
    )
    stopped_with(proc, "Mitsuba variant 'cuda_ad_rgb' is not available")
    assert listing(done) == before


def test_bad_libllvm_path_stops_before_any_job(done):
    before = listing(done)
    proc = rerender_all(done, env={"DRJIT_LIBLLVM_PATH": "/nonexistent/libLLVM.so"})
    stopped_with(proc, "DRJIT_LIBLLVM_PATH=/nonexistent/libLLVM.so")
    assert listing(done) == before


def test_mixed_back_ends_stop_before_any_job(done, tmp_path):
    # No libLLVM on this "machine": auto resolves to scalar_rgb, while the stored renders
    # were made with llvm_ad_rgb; rendering one scene again would mix them in Table 1.
    before = listing(done)
    target = f"{RENDERS}/scene_001/left/spp2/seeds0-1.zarr"
    env = {"DRJIT_LIBLLVM_PATH": None, "STEREOVAR_LLVM_SEARCH_DIRS": str(tmp_path)}
    proc = snakemake(done, "-j1", "--force", target, check=False, env=env)
    line = stopped_with(proc, "would mix back ends")
    assert "llvm_ad_rgb" in line and "scalar_rgb" in line and "allow_mixed_backends" in line
    assert listing(done) == before


def test_bad_spec_stops_before_any_job_and_lost_renders_come_back_from_the_cache(done):
    spec = done / "scenes/scene_001.yaml"
    good = spec.read_bytes()
    before, images = listing(done), radiance(done, "scene_001")
    spec.write_text(re.sub(r"fov_deg: ([0-9.]+)", r"fov_deg: \1x", good.decode(), count=1))
    line = stopped_with(snakemake(done, "-j2", "all", check=False), "camera.fov_deg")
    assert "scenes/scene_001.yaml" in line
    assert listing(done) == before
    spec.write_bytes(good)
    assert planned_jobs(done, "all") == {}
    # Renders lost anyway (deleted by hand, or by a job that failed after Snakemake removed
    # its outputs) come back from the render cache without a single render call.
    for view in ("left", "right"):
        subprocess.run(["rm", "-rf", str(done / f"{RENDERS}/scene_001/{view}")], check=True)
    snakemake(done, "-j2", "all")
    assert render_counts(done, "scene_001") == (0, 4)
    np.testing.assert_array_equal(radiance(done, "scene_001"), images)
    assert listing(done).keys() == before.keys()


def _rebuild(proc) -> str:
    text = proc.stdout + proc.stderr
    commands = re.findall(r"rebuild it with `([^`]+)`", text)
    errors = [ln for ln in text.splitlines() if "is damaged or incomplete" in ln]
    assert commands and errors, text
    assert all(ln.count("damaged") == 1 for ln in errors)  # one line each
    return commands[0]


def _damage(store: Path, array: str) -> None:
    """Overwrite the chunk files of one array of a Zarr store with garbage."""
    chunks = [p for p in (store / array).iterdir() if not p.name.startswith(".")]
    assert chunks
    for chunk in chunks:
        chunk.write_bytes(b"not a chunk")


ARRAYS = {
    "render": "radiance",
    "ground_truth": "disparity",
    "variance": "variance",
    "warp": "warped_variance",
}
"""The array of each store kind that its consumer reads."""


@pytest.mark.parametrize(
    ("store", "consumer", "rule"),
    [
        (f"{RUN}/intervention/scene_001.csv", f"{RUN}/tables/intervention.csv", "intervention"),
        (
            f"{RENDERS}/scene_001/right/spp2/seeds0-1.zarr",
            f"{RUN}/variance/scene_001/spp2.zarr",
            "render",
        ),
        (
            "results/ground_truth/scene_001.zarr",
            f"{RUN}/warped/scene_001/spp2.zarr",
            "ground_truth",
        ),
        (f"{RUN}/variance/scene_001/spp2.zarr", f"{RUN}/warped/scene_001/spp2.zarr", "variance"),
        (f"{RUN}/warped/scene_001/spp2.zarr", f"{RUN}/correlation/scene_001/spp2.csv", "warp"),
    ],
)
def test_damaged_store_names_the_one_job_that_rebuilds_it(done, store, consumer, rule):
    path = done / store
    if path.is_dir():
        _damage(path, ARRAYS[rule])
    else:
        path.write_text(path.read_text()[: len(path.read_text()) // 2])  # cut mid-row
    proc = snakemake(done, "-j1", "--force", consumer, check=False)
    assert proc.returncode != 0
    command = _rebuild(proc)
    args = shlex.split(command)
    assert args[:3] == ["stereovar", "run", "-j1"] and args[-3:] == [store, "--", "--force"]
    assert "--configfile" in args and str(done / "tiny.yaml") in args
    # the printed command, as printed, plans exactly the job that writes the store
    args = [sys.executable, "-m", "stereovar.cli", *args[1:]]
    run = subprocess.run([*args, "-n"], cwd=done, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    # the plan by stage: one job, of the rule that writes the store
    assert f"1 job ({rule} 1)" in run.stdout and "1 job in all" in run.stdout, run.stdout
    subprocess.run(args, cwd=done, capture_output=True, check=True)
    if rule == "render":
        assert render_counts(done, "scene_001") == (0, 4)
    # the failed consumer lost its output (Snakemake removes it before the job): rebuild it
    # for the next case, which reads it
    snakemake(done, "-j1", consumer)


def test_killed_run_resumes_with_the_same_command_and_renders_only_what_was_missing(
    tmp_path,
):
    # Renders slow enough (about 0.5 s each) to kill the run halfway through a batch.
    config = {
        **FAULT,
        "scenes": ["scene_000"],
        "resolution": {"width": 160, "height": 90},
        "render": {
            "spp": 64,
            "n_seeds": 4,
            "seeds_per_job": 4,
            "spp_sweep": {"scene": "scene_000", "spp": [64]},
        },
    }
    root = copy_workflow(tmp_path / "wf", config)
    # the renders and what reads them up to the correlation rows (the figures and tables of
    # `all` add nothing to a resumed render)
    target = "results/mitsuba/seeds/correlation/scene_000/spp64.csv"
    command = [sys.executable, "-m", "snakemake", "--configfile", "tiny.yaml", "-j2", target]
    proc = subprocess.Popen(
        command,
        cwd=root,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    cache = root / "cache/renders"
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and len(list(cache.glob("*/*.zarr"))) < 2:
        assert proc.poll() is None, "the run ended before it could be killed"
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    kept = len(list(cache.glob("*/*.zarr")))
    assert 2 <= kept < 8
    assert any((root / ".snakemake/locks").iterdir())  # the killed run's lock is left behind
    again = subprocess.run(command, cwd=root, capture_output=True, text=True)
    assert again.returncode == 0, again.stdout + again.stderr
    assert "removed the lock of an earlier run that was killed" in again.stderr
    log = (root / "logs/mitsuba/renders/scene_000/spp64/seeds0-3.log").read_text()
    m = re.search(r"(\d+) of 8 renders rendered, (\d+) from the render cache", log)
    assert m and (int(m.group(1)), int(m.group(2))) == (8 - kept, kept)
    assert (root / target).is_file()
    assert planned_jobs(root, target) == {}


def test_editing_a_mesh_an_xml_scene_reads_reruns_that_scene(tmp_path):
    root = copy_workflow(
        tmp_path / "wf",
        {
            **FAULT,
            "scenes": ["mine"],
            "render": {**FAULT["render"], "spp_sweep": {"scene": "mine", "spp": [2]}},
        },
    )
    xml = (REPO / "tests/test_xml_scene.py").read_text()
    xml = xml.split('XML = """', 1)[1].split('"""', 1)[0]
    wall = (
        '<shape type="obj"><string name="filename" value="meshes/wall.obj"/>'
        '<bsdf type="diffuse"/></shape>\n</scene>'
    )
    (root / "scenes/meshes").mkdir()
    (root / "scenes/meshes/wall.obj").write_text(
        "v -1 0 1.5\nv 1.6 0 1.5\nv 1.6 2 1.5\nv -1 2 1.5\nf 1 2 3\nf 1 3 4\n"
    )
    (root / "scenes/room.xml").write_text(xml.replace("</scene>", wall))
    (root / "scenes/mine.yaml").write_text("name: mine\nmitsuba_xml: room.xml\n")
    snakemake(root, "-j1", "results/ground_truth/mine.zarr")
    depth = open_dataset(root / "results/ground_truth/mine.zarr")["depth"].values.copy()
    assert planned_jobs(root, "results/ground_truth/mine.zarr") == {}
    mesh = root / "scenes/meshes/wall.obj"
    mesh.write_text(mesh.read_text().replace(" 1.5", " 1.2"))
    assert planned_jobs(root, "results/ground_truth/mine.zarr") == {"ground_truth": 1}
    assert planned_jobs(root, f"{RENDERS}/mine/left/spp2/seeds0-1.zarr") == {"render": 1}
    snakemake(root, "-j1", "results/ground_truth/mine.zarr")
    assert not np.array_equal(
        open_dataset(root / "results/ground_truth/mine.zarr")["depth"].values, depth
    )
    # a missing mesh and a malformed include are caught at start-up, in one line
    mesh.unlink()
    line = stopped_with(snakemake(root, "-n", "all", check=False), "wall.obj")
    assert "not found" in line
    mesh.write_text("v 0 0 1\nv 1 0 1\nv 1 1 1\nf 1 2 3\n")
    (root / "scenes/room.xml").write_text(xml.replace("</scene>", "<shape>"))
    stopped_with(snakemake(root, "-n", "all", check=False), "malformed XML")


def test_report_warns_when_the_results_come_from_another_config(done, tmp_path):
    same = snakemake(done, "--report", str(tmp_path / "same.html"))
    assert "does not match this config" not in same.stderr
    other = snakemake(
        done, "--report", str(tmp_path / "other.html"), config={"analysis": {"min_pixels": 31}}
    )
    warning = [ln for ln in other.stderr.splitlines() if ln.startswith("stereovar: warning")]
    assert len(warning) == 1 and "results/summary.json does not match this config" in warning[0]
