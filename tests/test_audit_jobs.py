"""An audit's import as workflow jobs: one `audit_import` job per frame with that frame's
files as inputs; nothing read or written while the workflow is parsed (dry runs, --lint,
--summary, --dag); a frame's changed file reruns only that frame; a touched file reruns
nothing, a file replaced keeping its size and mtime reruns its frame; a truncated file fails
its frame's job in one line and leaves everything else as it was."""

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from stereovar.audit.importer import import_record, sha256
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.io.images import read_image
from stereovar.io.store import open_dataset
from stereovar.io.writers import write_image

from .test_workflow import TINY, copy_workflow

pytestmark = pytest.mark.workflow

SMALL = {"width": 64, "height": 40, "n_seeds": 4}
BASE = "results/audit/synthetic"
FRAME_OUTPUTS = {
    frame: [
        f"{BASE}/renders/{frame}/left/spp0/seeds0-3.zarr",
        f"{BASE}/renders/{frame}/right/spp0/seeds0-3.zarr",
        f"{BASE}/ground_truth/{frame}.zarr",
        f"{BASE}/import/{frame}.json",
    ]
    for frame in ("f00", "f01")
}


def make_audit(root: Path):
    root = copy_workflow(root, TINY)
    settings, frames = write_synthetic_audit(
        root / "data", n_frames=2, render_format="pfm", **SMALL
    )
    (root / "audit.yaml").write_text(yaml.safe_dump({"audit": settings}))
    return root, settings, frames


def snakemake(root, *args, check=True):
    proc = subprocess.run(
        [sys.executable, "-m", "snakemake", "--configfile", "tiny.yaml", "audit.yaml", *args],
        cwd=root, capture_output=True, text=True,
    )
    if check:
        assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return proc


def planned(root) -> dict:
    """Rule to the wildcards of its jobs in a dry run."""
    out = snakemake(root, "-n", "all").stdout
    jobs = {}
    for block in re.split(r"\n\s*(?:local)?rule ", out)[1:]:
        rule = block.split(":", 1)[0].strip()
        m = re.search(r"wildcards: (.*)", block)
        jobs.setdefault(rule, []).append(m.group(1) if m else "")
    return jobs


@pytest.fixture(scope="module")
def audited(tmp_path_factory):
    """An audit of two synthetic frames, run to the verdict once."""
    root, settings, frames = make_audit(tmp_path_factory.mktemp("audit") / "wf")
    snakemake(root, "-j2", "all")
    return root, settings, frames


def test_parsing_writes_nothing_and_the_import_is_a_job_per_frame(tmp_path, tree_snapshot):
    root, settings, _ = make_audit(tmp_path / "wf")
    before = tree_snapshot(root)
    jobs = planned(root)
    assert sorted(jobs["audit_import"]) == ["scene=f00", "scene=f01"]
    assert "audit_verdict" in jobs
    for command in (["--lint"], ["--summary"], ["--dag"], ["--list-changes", "input"]):
        snakemake(root, *command)
    assert tree_snapshot(root) == before
    # the frame's files are its job's inputs, its stores and record its outputs
    out = snakemake(root, "-n", "-p", f"{BASE}/import/f00.json").stdout
    block = re.split(r"(?:local)?rule audit_import:", out)[1].split("\n\n", 1)[0]
    inputs = re.search(r"input: (.*)", block).group(1).split(", ")
    frame_files = [p for p in inputs if "/f00/" in p or p.endswith("/f00.pfm")]
    assert frame_files == inputs and len(inputs) == 2 * SMALL["n_seeds"] + 1
    outputs = [o.removesuffix(" (update)") for o in re.search(r"output: (.*)", block)
               .group(1).split(", ")]
    assert sorted(outputs) == sorted(FRAME_OUTPUTS["f00"])
    assert tree_snapshot(root) == before


def test_the_import_records_each_files_sha256(audited):
    root, settings, _ = audited
    for frame in ("f00", "f01"):
        record = json.loads((root / import_record("synthetic", frame)).read_text())
        assert record["frame"] == frame and len(record["files"]) == 2 * SMALL["n_seeds"] + 1
        for path, entry in record["files"].items():
            assert entry["sha256"] == sha256(path)
        left = open_dataset(root / FRAME_OUTPUTS[frame][0])
        assert left.attrs["source_sha256"] == [sha256(p) for p in left.attrs["source_files"]]
        log = (root / f"logs/audit/synthetic/import/{frame}.log").read_text()
        assert f"imported 1 frame ({frame})" in log
        assert (root / f"benchmarks/audit/synthetic/import/{frame}.tsv").is_file()


def test_one_frames_changed_file_reruns_only_that_frame(audited, tree_snapshot):
    root, settings, _ = audited
    assert planned(root) == {}
    # touched, bytes unchanged: nothing to do
    touched = settings["renders"].format(frame="f00", view="L", seed="001")
    os.utime(touched)
    assert planned(root) == {}
    # replaced by another file keeping size and mtime (cp -p, tar x): its frame only
    target = settings["renders"].format(frame="f00", view="R", seed="000")
    old = os.stat(target)
    other = str(root / "other.pfm")  # another render of the scene, of the same size
    write_image(other, read_image(target) * 1.01)
    shutil.copyfile(other, target)
    os.utime(target, ns=(old.st_atime_ns, old.st_mtime_ns))
    jobs = planned(root)
    assert jobs["audit_import"] == ["scene=f00"]
    # and a changed file of the other frame: that frame's import and what reads it
    changed = settings["renders"].format(frame="f01", view="L", seed="002")
    write_image(changed, read_image(changed) * 1.01)  # another render of the scene
    jobs = planned(root)
    assert sorted(jobs["audit_import"]) == ["scene=f00", "scene=f01"]
    for rule in ("variance", "warp", "correlation", "intervention", "audit_teaser"):
        assert len(jobs[rule]) == 2, (rule, jobs[rule])
    snakemake(root, "-j2", "all")
    assert planned(root) == {}
    # f01 alone: f00's stores untouched
    before = tree_snapshot(root / BASE / "renders/f00")
    write_image(changed, read_image(changed) * 0.99)
    jobs = planned(root)
    assert jobs["audit_import"] == ["scene=f01"]
    snakemake(root, "-j2", "all")
    assert tree_snapshot(root / BASE / "renders/f00") == before
    record = json.loads((root / import_record("synthetic", "f01")).read_text())
    assert record["files"][changed]["sha256"] == sha256(changed)


def test_a_truncated_file_fails_its_frames_import_in_one_line(audited, tree_snapshot):
    root, settings, _ = audited
    assert planned(root) == {}
    bad = settings["renders"].format(frame="f01", view="R", seed="001")
    data = Path(bad).read_bytes()
    # a verdict set aside by an earlier rerun in this module: this run sets its own aside
    shutil.rmtree(root / BASE / "previous", ignore_errors=True)
    before = tree_snapshot(root / "results")
    try:
        Path(bad).write_bytes(data[: len(data) // 3])
        proc = snakemake(root, "-j2", "all", check=False)
        assert proc.returncode != 0
        log = (root / "logs/audit/synthetic/import/f01.log").read_text()
        errors = [line for line in log.splitlines() if " ERROR " in line]
        assert len(errors) == 1 and errors[0].split(" ERROR ", 1)[1].startswith(
            f"error: {bad}: "
        ), log
        assert "Traceback" not in log
        after = tree_snapshot(root / "results")
        # Snakemake removes a job's outputs before it runs: f01's stores, made from the file
        # as it was, are gone (its record, update(), is put back); everything else is as it
        # was, byte for byte (the folders that held the stores aside: their mtimes change)
        gone = {str(Path(p).relative_to("results")) for p in FRAME_OUTPUTS["f01"][:3]}

        def kept(snapshot):
            return {
                k: v for k, v in snapshot.items()
                if not any(k == g or k.startswith(g + "/") or g.startswith(k + "/")
                           for g in gone)
            }

        record = str(Path(FRAME_OUTPUTS["f01"][3]).relative_to("results"))
        assert after[record][1] == before[record][1]  # put back by copying: bytes, not mtime
        after[record] = before[record]
        # the verdict made from f01's old stores is set aside before the import, bytes kept
        assert after.pop("audit/synthetic/previous")[1] is None  # the folder
        for name in ("verdict.md", "verdict.html", "summary.json"):
            old = before.pop(f"audit/synthetic/{name}")
            assert after.pop(f"audit/synthetic/previous/{name}") == old
        assert kept(after) == kept(before)
        assert not any(k in after for k in gone)
    finally:
        Path(bad).write_bytes(data)
    # the file put back, the same command imports the frame again (the analysis after it is
    # the changed-file test's)
    snakemake(root, "-j2", import_record("synthetic", "f01"))
    assert "audit_import" not in planned(root)
    record = json.loads((root / import_record("synthetic", "f01")).read_text())
    assert record["files"][bad]["sha256"] == sha256(bad)
