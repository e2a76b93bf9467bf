"""What an audit's import records is what it decoded: reimports decided on content, files
replaced while they are imported, one import-settings digest whether defaults are written out
or not, `stereovar audit` validating its config before running anything, temporaries of
killed imports, a dry run that writes nothing, and an export that says only what it wrote.
The import as workflow jobs: tests/test_audit_jobs.py."""

import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from stereovar import cli
from stereovar.audit import decoding, importer, run
from stereovar.audit.importer import import_audit, import_record
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.config import load_config
from stereovar.errors import AuditError, ConfigError
from stereovar.io.images import read_field, read_image
from stereovar.io.store import open_dataset
from stereovar.io.writers import write_field, write_image

REPO = Path(__file__).resolve().parents[1]
SCHEMA = REPO / "workflow/schemas/config.schema.yaml"
SMALL = {"width": 64, "height": 40, "n_seeds": 4}
RIGHT_F01 = "results/audit/synthetic/renders/f01/right/spp0/seeds0-3.zarr"


def file_sha256(path) -> str:
    """SHA-256 of a file's bytes, read in one piece."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def recorded(name="synthetic") -> dict:
    """Path to SHA-256 of every file in an audit's import records (one per frame)."""
    records = Path(import_record(name, "f00")).parent.glob("*.json")
    frames = [json.loads(p.read_text()) for p in records]
    return {p: r["sha256"] for f in frames for p, r in f["files"].items()}


def test_a_file_replaced_with_the_same_size_and_mtime_is_imported_again(tmp_path, monkeypatch):
    # cp -p, rsync -a and tar x keep size and mtime; PFM renders of one size have one length
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(tmp_path / "d", render_format="pfm", **SMALL)
    import_audit(settings)
    target = settings["renders"].format(frame="f01", view="R", seed="001")
    source = str(tmp_path / "other.pfm")  # another render of the scene, of the same size
    replacement = (frames[1].renders["right"][1] * 1.01).astype(np.float32)
    write_image(source, replacement)
    old = os.stat(target)
    shutil.copyfile(source, target)
    os.utime(target, ns=(old.st_atime_ns, old.st_mtime_ns))
    new = os.stat(target)
    assert (new.st_size, new.st_mtime_ns) == (old.st_size, old.st_mtime_ns)

    report = import_audit(settings)
    assert [f.name for f in report.frames if f.imported] == ["f01"]
    ds = open_dataset(RIGHT_F01)
    np.testing.assert_array_equal(ds["radiance"].values[1], replacement)
    assert recorded()[target] == file_sha256(target) == file_sha256(source)
    assert ds.attrs["source_sha256"] == [file_sha256(p) for p in ds.attrs["source_files"]]
    # and with nothing changed since, nothing is imported
    assert not any(f.imported for f in import_audit(settings).frames)


def _replace_file(path, data: bytes, how: str) -> None:
    """Put ``data`` at ``path``: a new file renamed over it, or the same file rewritten."""
    if how == "rename":
        tmp = Path(f"{path}.new")
        tmp.write_bytes(data)
        os.replace(tmp, path)
    else:
        with open(path, "r+b") as f:
            f.write(data)
            f.truncate()


@pytest.mark.parametrize("how", ["rename", "rewrite"])
@pytest.mark.parametrize("kind", ["render", "disparity"])
def test_a_file_replaced_while_it_is_imported_is_refused(tmp_path, monkeypatch, how, kind):
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    if kind == "render":
        target = settings["renders"].format(frame="f00", view="L", seed="002")
        spare = tmp_path / "spare.exr"
        write_image(spare, frames[0].renders["left"][2] * 1.01)  # another render
        name = "read_image"
    else:
        target = settings["disparity"].format(frame="f00")
        spare = tmp_path / "spare.pfm"
        write_field(spare, frames[0].disparity + 0.01)  # another estimate
        name = "read_field"
    replacement = spare.read_bytes()
    real = getattr(decoding, name)
    swapped = []

    def replaced_on_first_read(path, **options):
        if str(path) == target and not swapped:
            swapped.append(path)
            _replace_file(path, replacement, how)
        return real(path, **options)

    monkeypatch.setattr(decoding, name, replaced_on_first_read)
    with pytest.raises(AuditError) as err:
        import_audit(settings)
    message = str(err.value)
    assert swapped and "\n" not in message
    assert message.startswith(f"{target} changed while it was imported")
    assert not Path("results/audit/synthetic/renders").exists()
    assert not Path(import_record("synthetic", "f00")).exists()

    # the file is stable now: imported, and what is stored is what is recorded
    monkeypatch.setattr(decoding, name, real)
    import_audit(settings)
    assert recorded()[target] == file_sha256(target) == file_sha256(spare)
    gt = open_dataset("results/audit/synthetic/ground_truth/f00.zarr")
    left = open_dataset("results/audit/synthetic/renders/f00/left/spp0/seeds0-3.zarr")
    for ds in (gt, left):
        assert ds.attrs["source_sha256"] == [file_sha256(p) for p in ds.attrs["source_files"]]
    if kind == "render":
        np.testing.assert_array_equal(left["radiance"].values[2], read_image(spare))
    else:
        expected = read_field(spare)
        valid = gt["valid"].sel(view="left").values
        np.testing.assert_array_equal(gt["disparity"].sel(view="left").values[valid],
                                      expected[valid])


def test_the_settings_digest_does_not_depend_on_defaults_being_written_out(
    tmp_path, monkeypatch
):
    # the command line imported with the settings as written, the workflow with the
    # schema's defaults filled in: the same import
    monkeypatch.chdir(tmp_path)
    settings, _ = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    (tmp_path / "audit.yaml").write_text(yaml.safe_dump({"audit": settings}))
    filled = load_config([REPO / "config.yaml", tmp_path / "audit.yaml"], SCHEMA)["audit"]
    assert set(filled) > set(settings)  # defaults were filled
    assert import_audit(settings).frames[0].imported
    assert not import_audit(filled).frames[0].imported
    assert not import_audit(settings).frames[0].imported
    # a setting that changes the import still re-imports
    assert import_audit({**filled, "scale": 2.0}).frames[0].imported


def test_a_dry_run_plans_and_writes_nothing(tmp_path, monkeypatch, tree_snapshot):
    monkeypatch.chdir(tmp_path)
    settings, _ = write_synthetic_audit(tmp_path / "d", **SMALL)
    plan = import_audit(settings, dry_run=True)
    assert [f.name for f in plan.frames if f.imported] == ["f00", "f01"]
    assert plan.lines()[0].endswith(
        "would import 2 frames (f00, f01), 0 unchanged (dry run: nothing written)"
    )
    assert not Path("results").exists()
    import_audit(settings)
    path = settings["renders"].format(frame="f01", view="L", seed="000")
    write_image(path, read_image(path) + 1.0)
    before = tree_snapshot(tmp_path / "results")
    plan = import_audit(settings, dry_run=True)
    assert [f.name for f in plan.frames if f.imported] == ["f01"]
    assert tree_snapshot(tmp_path / "results") == before


def test_temporaries_of_killed_imports_are_removed_and_live_ones_kept(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, _ = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    import_audit(settings)
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()  # a process id that no process holds now
    folder = Path("results/audit/synthetic/renders/f00/left/spp0")
    dead = folder / f".seeds0-3.zarr.tmp-{gone.pid}-0123abcd"
    live = folder / f".seeds0-3.zarr.tmp-{os.getpid()}-89abcdef"
    dead_gt = Path(f"results/audit/synthetic/ground_truth/.f00.zarr.tmp-{gone.pid}-deadbeef")
    dead_record = Path(f"results/audit/synthetic/import/.f00.json.tmp-{gone.pid}-00ff00ff")
    for tmp in (dead, live, dead_gt):
        (tmp / "radiance").mkdir(parents=True)
        (tmp / "radiance" / "0.0.0.0").write_bytes(b"\0" * 1000)
    dead_record.write_text("{")
    other = folder / "notes.tmp-123-0123abcd"  # not a temporary's name: left alone
    other.write_text("kept")

    report = import_audit(settings)
    assert not dead.exists() and not dead_gt.exists() and not dead_record.exists()
    assert live.is_dir() and other.is_file()
    lines = [line for line in report.lines() if "temporar" in line]
    assert len(lines) == 1
    assert f"removed 3 temporaries of killed imports (process {gone.pid})" in lines[0]
    assert str(dead) in lines[0]
    assert not any(f.imported for f in report.frames)
    # nothing more to remove
    assert not any("temporar" in line for line in import_audit(settings).lines())


# --------------------------------------------------------------------------------------------
# stereovar audit: the config is validated before any file is read
# --------------------------------------------------------------------------------------------


@pytest.fixture
def project(tmp_path, monkeypatch):
    """A checkout to run `stereovar audit` in, with one synthetic frame and its config."""
    root = tmp_path / "project"
    root.mkdir()
    for name in ("Snakefile", "config.yaml"):
        shutil.copy(REPO / name, root / name)
    (root / "workflow").symlink_to(REPO / "workflow")
    settings, _ = write_synthetic_audit(root / "data", n_frames=1, **SMALL)
    monkeypatch.chdir(root)
    return root, settings


def run_cli(*args, capsys):
    rc = cli.main(list(args))
    out = capsys.readouterr()
    return rc, out.out, out.err


@pytest.mark.parametrize(
    "change",
    [
        {"audit": {"scale": "big"}},
        {"audit": {"bogus_key": 1}},
        {"bogus_key": 1},
        {"audit": {"convention": "sideways"}},
    ],
    ids=["wrong-type", "unknown-audit-key", "unknown-key", "bad-enum"],
)
@pytest.mark.parametrize("import_only", [True, False])
def test_cli_refuses_an_invalid_config_before_reading_any_file(
    project, capsys, monkeypatch, change, import_only
):
    root, settings = project
    config = {"audit": {**settings, **change.get("audit", {})}}
    config.update({k: v for k, v in change.items() if k != "audit"})
    (root / "bad.yaml").write_text(yaml.safe_dump(config))
    with pytest.raises(ConfigError) as expected:
        load_config([root / "config.yaml", root / "bad.yaml"], SCHEMA)

    def no_reading(*_args, **_kwargs):
        raise AssertionError("a file was read before the config was validated")

    monkeypatch.setattr(run, "discover", no_reading)
    monkeypatch.setattr(importer, "import_frame", no_reading)
    monkeypatch.setattr(cli, "_snakemake", no_reading)
    args = ["audit", "bad.yaml", *(["--import-only"] if import_only else [])]
    rc, out, err = run_cli(*args, capsys=capsys)
    assert rc == 2
    assert err == f"stereovar: error: {expected.value}\n"
    assert not (root / "results").exists()


def test_cli_runs_the_workflow_and_import_only_runs_only_the_imports(
    project, capsys, monkeypatch
):
    root, settings = project
    (root / "audit.yaml").write_text(yaml.safe_dump({"audit": settings}))
    runs = []
    monkeypatch.setattr(cli, "_snakemake", lambda args, where: runs.append(args) or 0)
    rc, out, _ = run_cli("audit", "audit.yaml", "--import-only", capsys=capsys)
    config = str((root / "audit.yaml").resolve())
    assert rc == 0 and runs == [["-j", "2", "all", "--configfile", config,
                                 "--until", "audit_import"]]
    assert out.startswith("imported synthetic: one record per frame in ")
    # the command itself imports nothing: what it wrote is the lock it held
    written = sorted(str(p.relative_to(root)) for p in (root / "results").rglob("*"))
    assert written == ["results/.locks", "results/.locks/audit-synthetic.lock"]


# --------------------------------------------------------------------------------------------
# stereovar export: a target that only looks like an export is refused
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("stand_in", ["link", "dangling-link", "folder"])
def test_export_refuses_a_target_that_would_pass_for_an_export(
    project, capsys, monkeypatch, tmp_path, stand_in
):
    root, _ = project
    config = load_config([root / "config.yaml"], SCHEMA)
    render = config["render"]
    scene = config["scenes"][1]
    target = root / f"results/export/{render['renderer']}/{render['estimator']}/exr/{scene}"
    target.parent.mkdir(parents=True)
    if stand_in == "folder":
        target.mkdir()
        (target / "renders").mkdir()
    else:
        elsewhere = tmp_path / "elsewhere"
        if stand_in == "link":
            elsewhere.mkdir()
        target.symlink_to(elsewhere)
    runs = []
    monkeypatch.setattr(cli, "_snakemake", lambda args, where: runs.append(args) or 0)
    rc, out, err = run_cli("export", "--format", "exr", capsys=capsys)
    assert rc == 2 and runs == [] and out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"stereovar: error: {target.relative_to(root)}")
    assert ("symbolic link" if "link" in stand_in else "holds no export") in lines[0]
