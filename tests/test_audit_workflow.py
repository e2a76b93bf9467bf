"""Audits end to end: our renders exported and audited again give the native numbers, and
synthetic renders with a known correlation give it back."""

import copy
import subprocess
import sys

import numpy as np
import pytest
import yaml

from stereovar import layout
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.io.store import open_dataset
from stereovar.io.tables import read_rows
from stereovar.io.writers import write_field
from stereovar.probe.training import load_matcher

from .test_workflow import SCENES, TINY, copy_workflow, snakemake

pytestmark = pytest.mark.workflow

ROUND = copy.deepcopy(TINY)
ROUND["render"].update({"n_seeds": 4, "seeds_per_job": 4})
ROUND["export"] = {"formats": ["exr", "pfm", "png"]}
NATIVE = "results/mitsuba/seeds"
NUMBERS = ("rho", "boot_low", "boot_high", "fisher_low", "fisher_high", "mean_a", "rho_corrected")


#: The native rows the round trips compare with: each scene's correlation rows at the main
#: SPP and its intervention rows (the sweep, figures and tables of ``all`` are not compared).
NATIVE_ROWS = [
    *(f"{NATIVE}/correlation/{scene}/spp2.csv" for scene in SCENES),
    *(f"{NATIVE}/intervention/{scene}.csv" for scene in SCENES),
]


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    root = copy_workflow(tmp_path_factory.mktemp("audit"), ROUND)
    snakemake(root, "-j2", "export", *NATIVE_ROWS)
    return root


def audit_of(root, fmt):
    settings = yaml.safe_load(
        (root / f"results/export/mitsuba/seeds/{fmt}/{SCENES[0]}/audit.yaml").read_text()
    )["audit"]
    # 4 seeds at 2 SPP: seed means too noisy for the photometric sign check to settle
    # the convention (the export's own, known); go on with it, as a team would
    settings["sign_check"] = "warn"
    snakemake(root, "-j2", "all", config={**ROUND, "audit": settings})
    return f"results/audit/{settings['name']}/seeds"


def compare(root, run, scene, *, rtol, atol, methods_atol=None):
    native = {(r["region"], r["method"]): r for r in read_rows(
        root / f"{NATIVE}/correlation/{scene}/spp2.csv")}
    audited = {(r["region"], r["method"]): r for r in read_rows(
        root / f"{run}/correlation/{scene}/spp2.csv")}
    assert native.keys() == audited.keys()
    worst = 0.0
    for key, n in native.items():
        for col in NUMBERS:
            a, b = float(n[col]), float(audited[key][col])
            if np.isnan(a):
                assert np.isnan(b), (key, col)
                continue
            tol = (methods_atol or {}).get(key[1], atol)
            assert b == pytest.approx(a, rel=rtol, abs=tol), (key, col, a, b)
            worst = max(worst, abs(a - b))
    return worst


@pytest.mark.parametrize("fmt", ["exr", "pfm"])
def test_exr_and_pfm_round_trip_give_the_native_numbers(exported, fmt):
    run = audit_of(exported, fmt)
    for scene in SCENES:
        compare(exported, run, scene, rtol=1e-5, atol=1e-7)
        native = read_rows(exported / f"{NATIVE}/intervention/{scene}.csv")
        audited = read_rows(exported / f"{run}/intervention/{scene}.csv")
        assert [r["value"] for r in audited] == pytest.approx(
            [r["value"] for r in native], rel=1e-5, abs=1e-9, nan_ok=True
        )
    page = (exported / run.replace("/seeds", "") / "verdict.md").read_text()
    assert "Monte Carlo-specific" in page and "teaser_scene_000.png" in page


def test_png16_with_kitti_disparity_round_trip_within_the_stated_tolerance(exported):
    """16-bit PNG renders: every statistic within 0.005 of the native float numbers, but the
    intensity-controlled rho: read knowing the files are integers, its control also removes
    the variance the 16-bit encoding implies (the pixels whose 4 frames fall on one code or
    two), which float renders do not have, and that moves it by about 0.01 on these
    4-seed, 2-SPP frames."""
    run = audit_of(exported, "png")
    worst = compare(exported, run, SCENES[0], rtol=0.01, atol=0.005,
                    methods_atol={"partial": 0.02})
    print(f"PNG16 + KITTI round trip: largest |difference| {worst:.4g}")


def test_synthetic_truth_is_recovered_by_the_corrected_rho(tmp_path, tree_snapshot):
    root = copy_workflow(tmp_path / "wf", TINY)
    settings, frames = write_synthetic_audit(
        root / "data", n_frames=2, width=160, height=96, n_seeds=16
    )
    settings["renders"] = "data/renders/{frame}/{view}/seed_{seed}.exr"
    settings["disparity"] = "data/disparity/{frame}.pfm"
    settings["mitigations"] = ["denoise"]  # from colour alone: an audit has no albedo/normal
    settings["probe"] = True  # the learned probe on the audit's frames, briefly trained
    probe = {"train_seeds": 2, "test_frames": 1, "conditions": ["none", "sensor_only", "denoise"],
             "planted": [], "architectures": ["mccnn"],
             "training": {"steps": 8, "crops": 2, "crop_rows": 8, "crop_cols": 24}}
    # one replicate of each design through the denoiser: its rows run at half the cost
    calibration = {"replicates": 4, "denoised_replicates": 1, "pipeline_replicates": 2}
    (root / "audit.yaml").write_text(yaml.safe_dump({"audit": settings, "probe": probe,
                                                     "calibration": calibration}))
    proc = subprocess.run(
        [sys.executable, "-m", "stereovar.cli", "audit", "audit.yaml"],
        cwd=root, capture_output=True, text=True,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "2 frames × 2 views × 16 seeds" in proc.stdout
    # again, nothing changed: nothing is imported, no job runs, nothing is written
    before = tree_snapshot(root / "results")
    again = subprocess.run(
        [sys.executable, "-m", "stereovar.cli", "audit", "audit.yaml"],
        cwd=root, capture_output=True, text=True,
    )
    assert again.returncode == 0, again.stderr[-3000:]
    assert "Nothing to be done" in again.stderr  # no import job either
    assert tree_snapshot(root / "results") == before
    summary = yaml.safe_load((root / "results/audit/synthetic/summary.json").read_text())
    rows = {(r["quantity"], r["region"]): r for r in summary["rows"]}
    corrected = rows[("attenuation-corrected rho", "all")]
    truth = float(np.mean([f.rho for f in frames]))
    assert corrected["low"] <= truth <= corrected["high"], (corrected, truth)
    assert summary["mc_specific"] is True
    # audit.mitigations: the audit's mitigation table, figure and verdict-page section
    base = root / "results/audit/synthetic"
    mitigations = {(r["mitigation"], r["region"]): r
                   for r in read_rows(base / "tables/mitigations.csv")}
    assert set(mitigations) == {("none", "all"), ("denoise", "all")}  # no mask: "all" only
    assert mitigations[("denoise", "all")]["psnr"] > mitigations[("none", "all")]["psnr"]
    assert open_dataset(base / "denoise/renders/f00/left/spp0/seeds0-15.zarr").attrs[
        "transform_aux"] == "none"
    page = (base / "verdict.md").read_text()
    assert "## Mitigations" in page and "- denoise: " in page
    assert "Monte Carlo-specific rho" in page.split("- denoise: ")[1].split("\n")[0]
    # the calibration step: its table, and its sentence on the page and in the summary
    assert (base / "tables/calibration.csv").is_file()
    assert summary["calibration"].startswith("On data like yours") and summary[
        "calibration"] in page
    assert rows[("Monte Carlo-specific rho", "all")]["low"] > 0
    assert "figures/mitigations.png" in page and (base / "figures/mitigations.png").is_file()
    assert summary["mitigations"][-1] in page
    # audit.probe: networks trained on one frame and tested on the other, for the baseline,
    # the control and the audit's mitigation; the page's section states the verdict
    probe_rows = read_rows(base / "tables/probe.csv")
    assert {r["tested"] for r in probe_rows} == {"none", "sensor_only", "denoise"}
    assert {r["region"] for r in probe_rows} == {"all"}  # no glass mask
    for fold, other in ((0, "f01"), (1, "f00")):
        for condition in ("none", "sensor_only", "denoise"):
            path = layout.probe_network("audit/synthetic", condition, "mccnn", "main", fold, 0)
            _, record = load_matcher(root / path)
            assert record["meta"]["scenes"] == [other]
    assert "## Learned probe" in page and summary["probe"]["paragraph"] in page
    assert "figures/probe.png" in page and (base / "figures/probe.png").is_file()
    # the glass rows are NaN with the reason, all is computed
    table = read_rows(root / "results/audit/synthetic/seeds/correlation/f00/spp0.csv")
    glass = [r for r in table if r["region"] == "glass"]
    assert glass and all(r["reason"] == "no material mask given" for r in glass)
    # the wrong convention stops before any statistic, in one line
    wrong = {**settings, "convention": "paper", "name": "wrong"}
    (root / "wrong.yaml").write_text(yaml.safe_dump({"audit": wrong}))
    proc = subprocess.run(
        [sys.executable, "-m", "stereovar.cli", "audit", "wrong.yaml"],
        cwd=root, capture_output=True, text=True,
    )
    assert proc.returncode != 0
    logs = sorted((root / "logs/audit/wrong/import").glob("*.log"))
    assert logs  # the import job that ran first stops the run (keep-going: false)
    for path in logs:  # each in one line
        log = path.read_text()
        errors = [line for line in log.splitlines() if " ERROR " in line]
        assert len(errors) == 1 and errors[0].endswith("set audit.convention: conventional")
    assert not (root / "results/audit/wrong/renders").exists()
    assert not (root / "results/audit/wrong/seeds").exists()


def test_export_to_a_symbolic_link_is_refused_and_a_real_one_reported(exported, tmp_path):
    # a link put where an export was: Snakemake finds the output present and writes nothing
    target = exported / f"results/export/mitsuba/seeds/exr/{SCENES[1]}"
    kept, empty = tmp_path / "kept", tmp_path / "empty"
    empty.mkdir()
    target.rename(kept)
    target.symlink_to(empty)
    command = [sys.executable, "-m", "stereovar.cli", "export", "--format", "exr",
               "--configfile", "tiny.yaml"]
    try:
        proc = subprocess.run(command, cwd=exported, capture_output=True, text=True)
    finally:
        target.unlink()
        kept.rename(target)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "is a symbolic link" in lines[0], lines
    assert "exported" not in proc.stdout and not any(empty.iterdir())
    # the export itself, up to date: what the message names is there
    proc = subprocess.run(command, cwd=exported, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.strip().splitlines()[-1] == (
        f"exported 2 scenes to results/export/mitsuba/seeds/exr/ ({', '.join(SCENES)}); "
        "each scene directory has an audit.yaml that audits it"
    )
    for scene in SCENES:
        assert (exported / f"results/export/mitsuba/seeds/exr/{scene}/audit.yaml").is_file()


def test_a_masked_audit_has_its_c_sigma_line_and_opens_with_the_decision(
    tmp_path, tiny_run_copy
):
    # the recommended set-up (docs/audit.md): a glass mask per frame; in a copy of the tiny
    # run, whose renders the audit's `all` would otherwise render again
    root = tiny_run_copy(tmp_path / "wf")
    settings, frames = write_synthetic_audit(
        root / "data", n_frames=2, width=96, height=64, n_seeds=8
    )
    mask = np.zeros((64, 96), np.uint8)
    mask[16:40, 30:70] = 255
    for k in range(2):
        write_field(root / f"data/mask_f{k:02d}.png", mask)
    settings.update(
        renders="data/renders/{frame}/{view}/seed_{seed}.exr",
        disparity="data/disparity/{frame}.pfm",
        glass_mask="data/mask_{frame}.png",
    )
    snakemake(root, "-j2", "all", config={**TINY, "audit": settings})
    base = root / "results/audit/synthetic"
    summary = yaml.safe_load((base / "summary.json").read_text())
    rows = {(r["quantity"], r["region"]): r for r in summary["rows"]}
    # the C_sigma line against the intervention CSVs: mean over frames of accuracy - chance
    lifts = {}
    for source, label in (("render", "renders"), ("sensor", "simulated camera frames")):
        per_frame = [
            r["value"] - r["chance"]
            for k in range(2)
            for r in read_rows(base / f"seeds/intervention/f{k:02d}.csv")
            if (r["cost"], r["metric"], r["condition"], r["region"], r["source"])
            == ("variance_cost", "wta_accuracy", "normal", "all", source)
        ]
        assert len(per_frame) == 2
        line = rows[(f"C_sigma WTA accuracy minus chance, {label}", "all")]
        assert line["value"] == pytest.approx(np.mean(per_frame), abs=1e-4)  # page rounding
        assert np.isfinite(line["low"]) and np.isfinite(line["high"])
        lifts[source] = line
    assert summary["matching_cue"] is not None
    # and the regions, from the mask
    regions = {r["region"] for r in read_rows(base / "seeds/intervention/f00.csv")}
    assert regions == {"all", "non_glass", "glass"}
    # the page: the decision first, then what was imported, a thumbnail per frame
    page = (base / "verdict.html").read_text()
    order = [page.index(s) for s in ('id="decision"', "What was imported", "Details")]
    assert order == sorted(order)
    assert summary["light"] in ("red", "amber", "green") and summary["decision"]
    import base64

    md = (base / "verdict.md").read_text()
    for k in range(2):  # embedded in the HTML page, linked from the Markdown one
        thumbnail = (base / f"figures/thumbnail_f{k:02d}.png").read_bytes()
        embedded = f'src="data:image/png;base64,{base64.b64encode(thumbnail).decode()}"'
        assert thumbnail and embedded in page
        assert f"(figures/thumbnail_f{k:02d}.png)" in md
    assert summary["shared_streams"] is False  # independent synthetic noise
    assert "residual rho at zero disparity" in page
