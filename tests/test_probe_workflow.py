"""The `probe` target end to end on a tiny config: networks, tiles, table, verdict (the audit's
probe runs in the synthetic audit of tests/test_audit_workflow.py)."""

import json
import math

import numpy as np
import pandas as pd
import pytest

from stereovar import layout
from stereovar.io.store import open_dataset
from stereovar.io.tables import read_rows
from stereovar.jobs.common import view_stack
from stereovar.probe.architectures import architecture
from stereovar.probe.experiment import scored_disparity
from stereovar.probe.inputs import network_input
from stereovar.probe.training import load_matcher
from stereovar.statistics.bootstrap import tile_labels

from .test_workflow import copy_workflow, planned_jobs, snakemake

pytestmark = pytest.mark.workflow

TINY_PROBE = {
    "scenes": ["scene_000", "scene_001"],
    "resolution": {"width": 96, "height": 40},
    "render": {
        "spp": 2,
        "n_seeds": 8,  # a judged seed-mean mitigation ships 4 images of 2 seeds each
        "seeds_per_job": 8,
        "spp_sweep": {"scene": "scene_000", "spp": [2]},
    },
    "analysis": {"bootstrap": {"tile": 8}},
    "mitigations": {"names": []},
    "probe": {
        "planted": [],
        "planted_series": {"costvolume": [2]},  # the architecture's own dose-response
        # judged on what it ships (sensor_only_shipped, with its twin); the control stays
        "mitigations": ["sensor_only"],
        "architectures": ["costvolume"],  # MC-CNN: the audit's probe, test_audit_workflow.py
        "folds": 2,
        "train_seeds": 2,
        "test_frames": 1,
        "training": {"steps": 8, "crops": 2, "crop_rows": 8, "crop_cols": 24, "check_every": 4,
                     "min_steps": 0, "patience": 1},
        "costvolume": {"steps": 6, "crops": 2, "crop_rows": 16, "crop_cols": 40,
                       "check_every": 3, "min_steps": 0, "patience": 1},
    },
}
CONDITIONS = ("none", "sensor_only", "sensor_only_shipped", "planted_x2")
VARIANTS = {"none": ("main", "twin"), "sensor_only": ("main",),
            "sensor_only_shipped": ("main", "twin"), "planted_x2": ("main", "twin")}
ARCHS = ("costvolume",)
INPUTS = ("normal", "shuffled", "camera", "camera_shuffled", "clean", "conflict")


@pytest.fixture(scope="module")
def probe_run(tmp_path_factory):
    """The tiny workflow after `snakemake -j2 probe`."""
    root = copy_workflow(tmp_path_factory.mktemp("probe"), TINY_PROBE)
    before = planned_jobs(root, "all")
    snakemake(root, "-j2", "probe")
    return root, before


def test_probe_is_not_part_of_all_until_it_has_run(probe_run):
    root, before = probe_run
    assert not any(rule.startswith("probe") for rule in before)
    after = planned_jobs(root, "all")
    assert not any(rule.startswith("probe") for rule in after), after
    assert planned_jobs(root, "probe") == {}


def test_every_network_is_saved_with_its_config_and_reloads(probe_run):
    root, _ = probe_run
    for arch in ARCHS:
        for condition in CONDITIONS:
            for variant in VARIANTS[condition]:
                for fold in (0, 1):
                    for j in (0, 1):
                        path = layout.probe_network("mitsuba", condition, arch, variant, fold, j)
                        _, record = load_matcher(root / path)
                        meta = record["meta"]
                        assert record["seed"] == j  # probe.seed 0 + training seed j
                        assert record["architecture"]["kind"] == arch
                        assert (meta["condition"], meta["variant"]) == (condition, variant)
                        assert meta["fold"] == fold
                        assert meta["factor"] == (2.0 if condition == "planted_x2" else None)
                        held_out = TINY_PROBE["scenes"][fold]
                        assert held_out not in meta["scenes"]
                        # one validation frame (the last image) of the one training scene:
                        # 8 renders, or 4 shipped images of 2 seeds each
                        shipped = condition == "sensor_only_shipped"
                        assert (meta["frames"], meta["validation_frames"]) == (
                            (3, 1) if shipped else (7, 1))
                        cap = TINY_PROBE["probe"]["training" if arch == "mccnn" else arch]
                        assert 1 <= meta["steps"] <= cap["steps"]
    planted = json.loads((root / layout.probe_planted("mitsuba")).read_text())
    assert planted["strengths"]["2"] == pytest.approx(2 * planted["strength"])
    assert set(planted["scenes"]) == set(TINY_PROBE["scenes"])


def test_tiles_match_the_saved_network_on_the_normal_input(probe_run):
    """Rescore one held-out scene with its saved network and compare with the tile table."""
    root, _ = probe_run
    fold, scene = 0, "scene_000"
    stores = layout.render_store("mitsuba", scene, "left", 2, "0-7")
    left = view_stack([root / stores])[0]
    right = view_stack([root / stores.replace("/left/", "/right/")])[0]
    gt = open_dataset(root / layout.traced_ground_truth(scene)).sel(view="left").load()
    sign = int(gt.attrs["disparity_sign"])
    d_gt = scored_disparity(gt, sign=sign)
    d_max = int(math.ceil(np.nanmax(np.where(gt["valid"], gt["disparity"], np.nan)))) + 4
    labels = tile_labels(d_gt.shape, 8)
    for arch in ARCHS:
        tiles = pd.read_csv(root / layout.probe_tiles("mitsuba", "none", arch, fold))
        net, _ = load_matcher(root / layout.probe_network("mitsuba", "none", arch, "twin", fold, 1))
        d_hat = architecture(arch).predict(
            net, [(network_input(left[0]), network_input(right[0]))], sign=sign,
            max_disparity=d_max,
        )[0]
        rows = tiles[
            (tiles.network == "none")
            & (tiles.variant == "twin")
            & (tiles.train_seed == 1)
            & (tiles.test_input == "normal")
            & (tiles.region == "all")
        ]
        assert set(rows.scene) == {scene} and set(rows.architecture) == {arch}
        scored = np.isfinite(d_gt) & np.isfinite(d_hat)
        for _, row in rows.iterrows():
            in_tile = scored & (labels == row.tile)
            err = np.abs(d_hat[in_tile] - d_gt[in_tile])
            assert row.n == in_tile.sum()
            assert row.hits == (err < 1).sum()
            assert row.zero == (np.abs(d_hat[in_tile]) < 0.5).sum()
            assert row.abs_error == pytest.approx(err.sum(), rel=1e-6, abs=1e-6)
        assert rows.n.sum() == scored.sum()


def test_the_table_pools_the_tiles_of_every_fold(probe_run):
    root, _ = probe_run
    tiles = pd.concat(
        pd.read_csv(root / layout.probe_tiles("mitsuba", c, a, f))
        for c in CONDITIONS
        for a in ARCHS
        for f in (0, 1)
    )
    table = read_rows(root / layout.probe_tables()[0])
    assert {(r["architecture"], r["tested"], r["test_input"]) for r in table} == {
        (a, c, t) for a in ARCHS for c in CONDITIONS for t in INPUTS
    }
    for row in table:
        own = tiles[
            (tiles.architecture == row["architecture"])
            & (tiles.tested == row["tested"])
            & (tiles.network == row["tested"])
            & (tiles.variant == "main")
            & (tiles.region == row["region"])
        ]
        per_seed = []
        for seed in sorted(set(own.train_seed)):
            part = own[(own.train_seed == seed) & (own.test_input == row["test_input"])]
            per_seed.append(part.hits.sum() / part.n.sum())
        assert row["accuracy"] == pytest.approx(np.mean(per_seed), abs=1e-12)
        if row["tested"] == "sensor_only":
            assert math.isnan(row["did_sensor"])  # the control against itself
        if row["test_input"] == "shuffled":  # every condition against its own twin
            if "twin" in VARIANTS[row["tested"]]:
                assert row["did_low"] <= row["did"] <= row["did_high"]
            else:  # the control, without a twin here
                assert math.isnan(row["did"])
        # both scenes' held-out tiles pooled
        assert set(own.scene) == set(TINY_PROBE["scenes"])
    trained = read_rows(root / layout.probe_training_tables()[0])
    assert {(r["architecture"], r["training"], r["variant"]) for r in trained} == {
        (a, c, v) for a in ARCHS for c in CONDITIONS for v in VARIANTS[c]
    }
    assert all(r["networks"] == 4 for r in trained)  # 2 folds x 2 training seeds
    for r in trained:  # each network's steps and how it stopped
        assert len(r["each"].split(", ")) == 4
        assert 0 <= r["collapsed"] <= (4 if r["variant"] == "main" else 0)
        if r["variant"] == "main":
            assert r["plateau"] + r["at_cap"] + r["collapsed"] == 4  # each counted once
            assert r["each"].count(" cap") == r["at_cap"]
            assert r["each"].count(" collapsed") == r["collapsed"]
        else:
            assert r["plateau"] == r["at_cap"] == 0  # a twin trains its network's steps


def test_the_verdict_states_the_shuffle_did_with_its_interval(probe_run):
    root, _ = probe_run
    verdict = json.loads((root / layout.probe_verdict()).read_text())
    table = read_rows(root / layout.probe_tables()[0])
    shuffle = next(
        r
        for r in table
        if (r["architecture"], r["tested"], r["test_input"], r["region"])
        == ("costvolume", "none", "shuffled", verdict["region"])
    )
    assert verdict["did"] == pytest.approx(shuffle["did"])
    assert verdict["uses_cue"] == (shuffle["did_low"] > 0)
    assert verdict["claim"]["answer"] == ("yes" if verdict["uses_cue"] else "no")
    assert set(verdict["architectures"]) == set(ARCHS)
    assert verdict["architectures"]["costvolume"]["did"] == pytest.approx(shuffle["did"])
    # the mitigation row (probe.mitigations: sensor_only on what it ships, against its own
    # twin, judged against none) and the planted dose-response of the architecture's series
    cv = verdict["architectures"]["costvolume"]
    (mitigation,) = cv["mitigations"]
    sensor = next(r for r in table if (r["architecture"], r["tested"], r["test_input"],
                                       r["region"]) == ("costvolume", "sensor_only_shipped",
                                                        "shuffled", verdict["region"]))
    assert (mitigation["condition"], mitigation["mitigation"]) == ("sensor_only_shipped",
                                                                   "sensor_only")
    assert mitigation["did"] == pytest.approx(sensor["did"])
    assert mitigation["status"] != "not testable" and "what it ships" in mitigation["note"]
    assert [p["factor"] for p in cv["power"]] == [2.0]
    assert cv["detected_from_factor"] == (2.0 if cv["power"][0]["detected"] else None)
    assert "sensor_only" in cv["paragraph"] and "x2" in cv["paragraph"]
    assert (root / layout.probe_figure()).stat().st_size > 0


def test_claims_take_the_probe_once_it_has_run(probe_run):
    root, _ = probe_run
    out = snakemake(root, "-n", "--forceall", "-p", "claims").stdout
    assert layout.probe_verdict() in out


USER_MODEL = '''
import torch
from torch import nn


class Wta(nn.Module):
    """(left, right) sRGB (B, 3, H, W) -> disparity (B, 1, H, W), right pixel at x - d."""

    def __init__(self, max_disparity=8):
        super().__init__()
        self.features = nn.Conv2d(3, 8, 5, padding=2)
        self.max_disparity = max_disparity

    def forward(self, left, right):
        fl, fr = self.features(left), self.features(right)
        width = fr.shape[-1]
        costs = [
            (fl * nn.functional.pad(fr, (d, 0))[..., :width]).sum(1)
            for d in range(self.max_disparity + 1)
        ]
        return torch.stack(costs, 1).argmax(1, keepdim=True).float()


def factory():
    return Wta()
'''


def test_stereovar_probe_runs_the_users_model_on_the_runs_frames(probe_run):
    """`stereovar probe --model module:factory --weights FILE`, end to end on the run's
    renders: the loading, the frames' stores, the counterfactual inputs, the table and the
    one-line reading (whether a network uses the cue is tests/test_probe_user_model.py's)."""
    import subprocess
    import sys

    import torch

    root, _ = probe_run
    (root / "user_models.py").write_text(USER_MODEL)
    sys.path.insert(0, str(root))
    try:
        from user_models import factory
    finally:
        sys.path.remove(str(root))
    torch.manual_seed(0)
    torch.save(factory().state_dict(), root / "weights.pt")
    command = [sys.executable, "-m", "stereovar.cli", "probe", "--model", "user_models:factory"]
    proc = subprocess.run(
        [*command, "--weights", "weights.pt", "--test-frames", "2", "--config", "tiny.yaml"],
        cwd=root, capture_output=True, text=True,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    rows = read_rows(root / layout.probe_model_tables("mitsuba")[0])
    names = {r["row"] for r in rows}
    assert {"mc_shuffle", "camera_shuffle", "mc_minus_camera"} <= names, names
    assert "shuffle" in proc.stdout and "probe_model.md" in proc.stdout
    missing = subprocess.run(
        [*command, "--weights", "nowhere.pt"], cwd=root, capture_output=True, text=True
    )
    assert missing.returncode != 0
    assert len(missing.stderr.strip().splitlines()) == 1 and "nowhere.pt" in missing.stderr


def test_too_few_renders_stop_the_probe_in_one_line_before_any_job(probe_run):
    root, _ = probe_run
    few = {"render": {"n_seeds": 3, "seeds_per_job": 3}}
    proc = snakemake(root, "-n", "probe", check=False, config=few)
    assert proc.returncode != 0
    lines = [line for line in proc.stderr.splitlines() if line.startswith("stereovar:")]
    assert len(lines) == 1 and "at least 4 renders per view" in lines[0], proc.stderr[-2000:]
    # enough for the probe, too few for 4 shipped images of 2 seeds of the judged sensor_only
    six = {"render": {"n_seeds": 6, "seeds_per_job": 6}}
    proc = snakemake(root, "-n", "probe", check=False, config=six)
    assert proc.returncode != 0
    lines = [line for line in proc.stderr.splitlines() if line.startswith("stereovar:")]
    assert len(lines) == 1 and "needs 8 renders per view" in lines[0], proc.stderr[-2000:]
    assert "probe.mitigations" in lines[0] and "there are 6" in lines[0]
    (root / "override.yaml").unlink()
    # (the main experiment plans at N = 2 without a probe job: tests/test_workflow.py)
