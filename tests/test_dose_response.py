"""The dose-response of a seed-mean mitigation (stereovar.calibration.dose_response,
stereovar.statistics.dose_response): known answers on synthetic scenes, the table's
arithmetic and the plan's one-line refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter, shift

from stereovar.calibration.dose_response import dose_rows
from stereovar.calibration.scene_frames import SceneFrames
from stereovar.errors import ConfigError
from stereovar.statistics.dose_response import dose_findings, dose_table, removal_budgets
from stereovar.statistics.fields import AnalysisSettings

H, W, D = 64, 96, 2.0


@pytest.fixture(scope="module")
def dose_scene(textured_pair):
    """A function of the cue: the textured pair, right view the left 2 px over, whose Monte
    Carlo variance is 2.5 times a camera law times exp(cue * z) with z one smooth pattern both
    views share at the disparity (the cross-view cue; 0: none)."""
    mean, truth = textured_pair(H, W, D, 5)
    rng = np.random.default_rng(6)
    pattern = gaussian_filter(rng.normal(0.0, 1.0, (H, W)), 2.0)
    pattern /= pattern.std()
    z = {"left": pattern, "right": shift(pattern, (0, D), order=1, mode="nearest")}

    def make(cue: float) -> SceneFrames:
        variance = {v: 2.5 * (m.mean(axis=-1) / 1000.0 + 4e-6) * np.exp(cue * z[v])
                    for v, m in mean.items()}
        return SceneFrames(mean, variance, truth, np.zeros((H, W), bool), 1, 8, "dose|spp32")

    return make


def _by_point(rows):
    table = dose_table([{**r, "scene": "s"} for r in rows], spp=32)
    return {(r["gain"], r["multiple"]): r for r in table if r["kind"] == "predicted"}


@pytest.fixture(scope="module")
def cue_points(dose_scene):
    rows = dose_rows(dose_scene(1.0), transform="sensor_only", settings=AnalysisSettings(),
                     cameras=[{"gain": 1000.0, "read_noise": 2.0},
                              {"gain": 10.0, "read_noise": 2.0}],
                     multiples=(1, 16), replicates=2)
    return _by_point(rows)


def test_a_shared_variance_pattern_reads_in_what_ships_and_fades_with_the_budget(cue_points):
    """A cue twice the camera's noise reads clearly in what sensor_only ships at the
    measured budget, falls as the budget grows (the Monte Carlo part falls as 1/S, the
    camera's does not), and under a camera a hundred times noisier is gone."""
    base, far = cue_points[(1000.0, 1)], cue_points[(1000.0, 16)]
    assert base["mc_specific_low"] > 0.1 and base["mc_cue"] == "remains"
    assert far["mc_specific"] < base["mc_specific"] - 0.05
    noisy = cue_points[(10.0, 1)]
    assert abs(noisy["mc_specific"]) < 0.05 and noisy["mc_specific_low"] < 0.05
    # the shipped image's error: the 1/S Monte Carlo part plus the camera's law
    assert far["psnr"] > base["psnr"] > noisy["psnr"]
    assert base["shipped_spp"] == 64 and far["shipped_spp"] == 1024
    assert far["render_cost"] == 32.0


def test_without_a_cue_what_ships_reads_its_null(dose_scene):
    """No shared pattern: the Monte Carlo variance is a camera law, and the predicted
    difference from the null covers 0 (no false cue from the path itself)."""
    rows = dose_rows(dose_scene(0.0), transform="sensor_only", settings=AnalysisSettings(),
                     cameras=[{"gain": 1000.0, "read_noise": 2.0}], multiples=(1,),
                     replicates=2)
    (row,) = _by_point(rows).values()
    assert row["mc_specific_low"] < 0.0 < row["mc_specific_high"] + 0.02
    assert abs(row["mc_specific"]) < 0.05


def test_renders_at_a_budget_are_measured_against_the_same_null(dose_scene):
    """Frames given at a multiple are measured as ``renders`` beside the prediction, and
    the table gives them as ``measured`` with the null of that budget and camera."""
    scene = dose_scene(1.0)
    rng = np.random.default_rng(9)
    renders = {v: np.stack([m + rng.normal(0.0, 1.0, m.shape) * np.sqrt(scene.variance[v])
                            [..., None] for _ in range(8)]).astype(np.float32)
               for v, m in scene.mean.items()}
    rows = dose_rows(scene, transform="sensor_only", settings=AnalysisSettings(),
                     cameras=[{"gain": 1000.0, "read_noise": 2.0}], multiples=(1,),
                     replicates=2, renders={1: renders})
    assert sum(r["kind"] == "renders" for r in rows) == 1
    table = dose_table([{**r, "scene": "s"} for r in rows], spp=32)
    kinds = {r["kind"]: r for r in table}
    assert set(kinds) == {"predicted", "measured"}
    # the renders carry the same cue: the measurement agrees with the prediction
    assert abs(kinds["measured"]["mc_specific"] - kinds["predicted"]["mc_specific"]) < 0.1
    assert kinds["measured"]["null_partial"] == kinds["predicted"]["null_partial"]


def _row(kind, multiple, value, half=0.02, margin=0.1, gain=30.0):
    return {"transform": "sensor_only", "gain": gain, "read_noise": 2.0, "multiple": multiple,
            "shipped_spp": 64 * multiple, "render_cost": 2.0 * multiple, "kind": kind,
            "mc_specific": value, "mc_specific_low": value - half,
            "mc_specific_high": value + half, "margin": margin, "margin_strength": 0.5,
            "psnr": 20.0,
            "mc_cue": "removed" if abs(value) + half < margin and value - half <= 0.05
            else "remains"}


def test_the_removal_budget_is_the_smallest_predicted_removed_with_its_measurement():
    table = [_row("predicted", 1, 0.2), _row("predicted", 4, 0.03), _row("predicted", 16, 0.01),
             _row("measured", 1, 0.22), _row("measured", 4, 0.09)]
    (b,) = removal_budgets(table)
    assert b["predicted"]["multiple"] == 4 and b["measured_there"]["mc_cue"] == "remains"
    assert b["verified"] is None
    (line,) = dose_findings(table)
    assert "predicted removed from 256 SPP per image (8x the render time" in line
    assert "but measured 0.090 [0.070, 0.110] there, remains: the prediction is optimistic" \
        in line


def test_no_budget_that_removes_it_is_said_with_the_numbers():
    table = [_row("predicted", m, 0.2 / math.sqrt(m), margin=0.04, gain=1000.0)
             for m in (1, 4, 16)]
    (line,) = dose_findings(table)
    assert line.startswith("sensor_only with a camera of gain 1000 e- per unit")
    assert "no budget up to 1024 SPP per image removes it (predicted 0.050 [0.030, 0.070]" in line


def test_the_plan_refuses_a_transform_that_ships_no_seed_mean():
    from stereovar.mitigations import mitigation_runs
    from stereovar.workflow_inputs.mitigations import dose_response_plan

    config = {
        "scenes": ["a"], "render": {"renderer": "mitsuba", "spp": 32},
        "mitigations": {"names": ["spp_x4", "denoise", "sensor_only"],
                        "dose_response": {"transforms": ["sensor_only"], "gains": [30],
                                          "multiples": [1, 4, 16]}},
        "controls": {"sensor": {"gain": 1000, "read_noise": 2.0}},
        "render_spp": 32,
    }
    runs = mitigation_runs(config)
    plan = dose_response_plan(config, runs)
    assert plan["cameras"] == [{"gain": 1000.0, "read_noise": 2.0},
                               {"gain": 30.0, "read_noise": 2.0}]
    assert plan["rendered"] == [1, 4]
    config["mitigations"]["dose_response"]["transforms"] = None  # the default
    assert dose_response_plan(config, runs)["transforms"] == ["sensor_only"]
    without = mitigation_runs({**config, "mitigations": {**config["mitigations"],
                                                          "names": ["denoise"]}})
    assert dose_response_plan(config, without)["transforms"] == []
    config["mitigations"]["dose_response"]["transforms"] = ["denoise"]
    with pytest.raises(ConfigError, match=r"dose_response.transforms.*'denoise'.*sensor_only"):
        dose_response_plan(config, runs)


def test_the_table_job_writes_every_format_with_the_budget_in_its_caption(tmp_path):
    """The table job reads every scene's rows and the calibration's nulls (the margin of what
    sensor_only ships) and says in its caption which budget and camera remove the cue."""
    from stereovar.calibration.dose_response import DOSE_COLUMNS
    from stereovar.io.tables import read_rows, write_tables
    from stereovar.jobs.dose_response import dose_response_table_job

    rng = np.random.default_rng(3)
    rows = []
    for scene in ("a", "b"):
        for m, value in ((1, 0.3), (4, 0.01)):
            for kind in ("predicted", "null"):
                for r in range(2):
                    rho = (value if kind == "predicted" else 0.0) + float(rng.normal(0, 0.002))
                    rows.append({"scene": scene, "transform": "sensor_only", "gain": 30.0,
                                 "read_noise": 2.0, "multiple": m, "shipped_spp": 64 * m,
                                 "kind": kind, "replicate": r, "rho": rho,
                                 "boot_low": rho - 0.01, "boot_high": rho + 0.01,
                                 "chance_se": 0.005, "mse": 0.01})
    paths = []
    for scene in ("a", "b"):
        path = tmp_path / f"{scene}.csv"
        write_tables([r for r in rows if r["scene"] == scene], DOSE_COLUMNS, {"csv": str(path)})
        paths.append(str(path))
    nulls = tmp_path / "nulls.csv"
    write_tables([{"scene": "a", "transform": "sensor_only|shipped", "region": "all",
                   "method": "partial", "null_rho": 0.0, "null_se": 0.001, "margin": 0.1,
                   "margin_strength": 0.5}], ["scene", "transform", "region", "method",
                                              "null_rho", "null_se", "margin",
                                              "margin_strength"], {"csv": str(nulls)})
    outputs = {fmt: str(tmp_path / f"dose.{fmt}") for fmt in ("csv", "md", "tex", "html")}
    table = dose_response_table_job(paths, outputs, nulls=str(nulls), spp=32)
    assert [(r["multiple"], r["mc_cue"]) for r in table] == [(1, "remains"), (4, "removed")]
    assert len(read_rows(outputs["csv"])) == 2
    text = (tmp_path / "dose.md").read_text()
    assert "predicted removed from 256 SPP per image (8x the render time" in text
    assert "margin 0.1: no cue as strong as 0.5x the renders' own survives" in text
