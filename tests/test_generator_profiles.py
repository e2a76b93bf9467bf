"""Generator profiles: the presets, their scaling to a budget, and the generator table."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from stereovar.errors import ConfigError
from stereovar.generators import (
    PAPER,
    PROFILES,
    GeneratorProfile,
    automatic_min_samples,
    budget_profile,
    generator_profiles,
    load_profile,
    profile_path,
)
from stereovar.renderers.cycles.settings import cycles_options, cycles_options_error
from stereovar.statistics.generators import GENERATOR_COLUMNS, compact_table, generator_rows


@pytest.mark.parametrize("name", PROFILES)
def test_every_preset_is_a_valid_cycles_config_citing_its_source(name):
    path = profile_path(name)
    text = path.read_text()
    profile = load_profile(name)
    # the settings pass the renderer's own validation once its defaults are filled in
    assert cycles_options_error(cycles_options(profile.cycles)) is None
    # the preset cites the generator's repository at a commit, with line numbers
    assert re.search(r"@ [0-9a-f]{40}", text.splitlines()[0])
    cited = re.findall(r"^#\s+\S+\.(?:py|gin) L\d+", text, flags=re.M)
    assert len(cited) >= 3
    # and is a config file of its own, merged on the default config as --configfile does
    from stereovar.config import load_config
    from stereovar.workflow_home import workflow_root

    root = workflow_root()
    config = load_config(
        [root / "config.yaml", path], root / "workflow" / "schemas" / "config.schema.yaml"
    )
    assert config["render"]["renderer"] == "cycles"
    assert config["render"]["spp"] == profile.spp
    assert {k: config["render"]["cycles"][k] for k in profile.cycles} == profile.cycles


def test_cycles_automatic_minimum_follows_its_formula():
    for tau in (0.1, 0.05, 0.01, 0.005, 0.001):
        expected = max(4, math.ceil(16.0 / tau**0.3))
        assert automatic_min_samples(tau) == expected
    # the comment in Cycles' source: 0.1 -> 32, 0.01 -> 64, 0.001 -> 128
    assert [automatic_min_samples(t) for t in (0.1, 0.01, 0.001)] == [32, 64, 128]


def test_a_profile_within_the_budget_is_unchanged():
    p = GeneratorProfile("x", 32, {"adaptive_sampling": True, "adaptive_threshold": 0.02})
    assert budget_profile(p, 64) is p


@pytest.mark.parametrize("spp,budget", [(1024, 64), (8192, 64), (128, 64), (300, 100)])
def test_scaling_keeps_the_share_of_the_budget_where_pixels_stop(spp, budget):
    tau = 0.01
    p = GeneratorProfile("x", spp, {"adaptive_sampling": True, "adaptive_threshold": tau})
    q = budget_profile(p, budget)
    k = spp / budget
    assert q.spp == budget and math.isclose(q.scale, 1 / k)
    # error ~ 1/sqrt(n): the threshold a pixel reaches at n/k samples is sqrt(k) times higher
    assert math.isclose(q.cycles["adaptive_threshold"], tau * math.sqrt(k), rel_tol=1e-4)
    # the automatic minimum, a share of the generator's SPP, keeps that share of the budget
    share = automatic_min_samples(tau) / spp
    assert abs(q.cycles["adaptive_min_samples"] - share * budget) <= 0.5 or (
        q.cycles["adaptive_min_samples"] == 1
    )
    # the preset's own settings are left alone
    assert p.cycles["adaptive_threshold"] == tau


def test_non_adaptive_profiles_only_lose_samples():
    q = budget_profile(GeneratorProfile("k", 128, {"denoise": True}), 64)
    assert (q.spp, q.scale, q.cycles) == (64, 0.5, {"denoise": True})


def test_budget_below_one_is_refused_in_one_line():
    with pytest.raises(ConfigError, match="generators.spp"):
        budget_profile(GeneratorProfile("k", 128), 0)


def test_the_rows_put_the_paper_first_and_name_unknown_profiles():
    config = {"generators": {"profiles": list(PROFILES), "spp": 64}}
    rows = generator_profiles(config)
    assert [r.name for r in rows] == [PAPER, *PROFILES]
    assert rows[0].seed_rule == "per_view" and rows[0].seed_policy == "independent"
    assert all(r.spp <= 64 for r in rows)
    with pytest.raises(ConfigError, match="no generator profile 'nope'; use any of"):
        generator_profiles({"generators": {"profiles": ["nope"], "spp": 64}})


@pytest.mark.parametrize(
    "cycles,rule,policy",
    [
        ({}, "per_view", "independent"),
        ({"seed": "unset"}, "unset", "shared"),
        ({"seed": "animated"}, "animated", "shared"),
        ({"multiview": True, "seed": "unset"}, "multiview", "shared"),
    ],
)
def test_seed_rules_map_to_the_seed_policy_they_imply(cycles, rule, policy):
    p = GeneratorProfile("x", 64, cycles)
    assert (p.seed_rule, p.seed_policy) == (rule, policy)


def test_generator_rows_carry_the_profile_and_every_column():
    p = budget_profile(GeneratorProfile("blenderproc", 1024, {"denoise": True,
                                                             "denoiser": "compositor"}), 64)
    measured = [{"region": "all", "mc_specific": 0.2, "mc_specific_low": 0.1,
                 "mc_specific_high": 0.3, "null_partial": 0.5, "mc_cue": "remains"}]
    rows = generator_rows(p, measured, generator_spp=1024, matched="denoise")
    assert set(rows[0]) == set(GENERATOR_COLUMNS)
    assert rows[0]["denoiser"] == "compositor" and rows[0]["spp_scale"] == 1 / 16
    assert "OIDN" in rows[0]["matched_null"]
    text = compact_table(rows)[0]
    assert text["SPP"] == "64 of 1024 (x1/16)"
    assert text["matched null"] == "0.500"
    assert math.isnan(rows[0]["psnr"]) and text["PSNR"] == "n/a"


def _generator_run(tmp_path, name, transform, rng, cycles, *, chain=None, shipped=None):
    """One profile's inputs of the generator job, as CSV files: two scenes' correlation and
    mitigation rows, and 16 calibration replicates per scene through the profile's matched
    transform (cue-free camera and misaligned nulls, a planted cue). With ``chain``, the
    replicates also pass through it, and ``shipped`` (method to rho) gives each scene's
    rows of what ships (kind ``renders``)."""
    from stereovar.calibration.replicates import CALIBRATION_COLUMNS
    from stereovar.io.tables import write_tables

    paths = {"correlation": [], "scene_rows": [], "calibration": []}
    for scene in ("a", "b"):
        corr = []
        for method in ("warp", "partial"):
            rho = float(rng.uniform(0.2, 0.6))
            corr.append({"scene": scene, "region": "all", "method": method, "rho": rho,
                         "boot_low": rho - 0.05, "boot_high": rho + 0.05, "n_seeds": 8})
        scene_rows = [{"scene": scene, "region": "all", "quantity": q, "value": v,
                       "low": v - 0.01, "high": v + 0.01}
                      for q, v in (("residual_rho_zero", 0.0), ("psnr", 25.0))]
        replicates = []
        for r in range(16):
            for t in dict.fromkeys(["none", transform, *([chain] if chain else [])]):
                for kind, factor, mean in (("camera", 0.0, 0.0), ("misaligned", 0.0, 0.0),
                                           ("planted", 1.0, 0.3)):
                    rho = float(rng.normal(mean, 0.02))
                    replicates.append({
                        "scene": scene, "replicate": r, "kind": kind, "strength": factor,
                        "strength_factor": factor, "transform": t, "region": "all",
                        "method": "partial", "rho": rho, "boot_low": rho - 0.04,
                        "boot_high": rho + 0.04, "chance_se": math.nan, "n_pixels": 1000,
                    })
        for method, rho in (shipped or {}).items():
            replicates.append({
                "scene": scene, "replicate": 0, "kind": "renders", "strength": math.nan,
                "strength_factor": math.nan, "transform": chain, "region": "all",
                "method": method, "rho": rho, "boot_low": rho - 0.04, "boot_high": rho + 0.04,
                "chance_se": math.nan, "n_pixels": 1000,
            })
        for key, rows, columns in (
            ("correlation", corr, list(corr[0])),
            ("scene_rows", scene_rows, list(scene_rows[0])),
            ("calibration", replicates, CALIBRATION_COLUMNS),
        ):
            path = tmp_path / name / key / f"{scene}.csv"
            path.parent.mkdir(parents=True, exist_ok=True)
            write_tables(rows, columns, {"csv": str(path)})
            paths[key].append(str(path))
    return {"profile": name, "spp": 64, "generator_spp": 128, "scale": 0.5, "cycles": cycles,
            "calibration_transform": transform, "output_transform": chain, **paths}


def test_the_generator_job_keeps_its_verdicts_calibration_and_quotes_its_upper_bound(
    tmp_path,
):
    """The calibration each profile's verdict is measured against is written beside the
    table (every check, with the profile), and the table's caption gives the verdict rule's
    false-positive rate by the upper end of its interval, scenes combined."""
    from stereovar.calibration.summary import CALIBRATION_TABLE_COLUMNS, calibration_table
    from stereovar.io.tables import read_rows
    from stereovar.jobs.generators import generators_table_job

    rng = np.random.default_rng(11)
    runs = [_generator_run(tmp_path, "paper", "none", rng, {}),
            _generator_run(tmp_path, "kubric", "denoise", rng, {"denoise": True})]
    outputs = {fmt: str(tmp_path / f"generators.{fmt}") for fmt in ("csv", "md")}
    kept = tmp_path / "generators_calibration.csv"
    generators_table_job(runs, outputs, calibration=str(kept))
    rows = read_rows(kept)
    assert list(rows[0]) == ["profile", *CALIBRATION_TABLE_COLUMNS]
    caption = (tmp_path / "generators.md").read_text()
    for run in runs:
        expected, _ = calibration_table([r for p in run["calibration"] for r in read_rows(p)])
        got = [r for r in rows if r["profile"] == run["profile"]]
        assert [(r["check"], r["scope"], r["transform"], r["kind"], r["n"]) for r in got] == [
            (r["check"], r["scope"], r["transform"], r["kind"], r["n"]) for r in expected
        ]
        verdict = [r for r in got if r["check"] == "false_positive_rate"
                   and r["rule"] == "above_null" and r["scope"] == "combined"
                   and r["transform"] == run["calibration_transform"]]
        upper = max(r["high"] for r in verdict)
        assert upper > 0.05  # 16 replicates cannot show the 5% level
        assert f"{run['profile']} at most {math.ceil(100 * upper)}%" in caption
    assert "not shown" in caption and "generators_calibration.csv" in caption


def test_the_generator_table_gives_what_ships_beside_the_float_verdict(tmp_path):
    """Each profile's row carries the verdict on what it ships, against the nulls drawn
    through the same chain (denoiser, then PNG): a cue of 0.3 over nulls at 0 remains with
    its interval; an output whose codes fix the variance at 97% of pixels reads "not
    testable" with that share, never "removed"; a float profile ships its EXR."""
    from stereovar.io.tables import read_rows
    from stereovar.jobs.generators import generators_table_job

    rng = np.random.default_rng(12)
    runs = [
        _generator_run(tmp_path, "paper", "none", rng, {}),
        _generator_run(tmp_path, "kubric", "denoise", rng, {"denoise": True},
                       chain="denoise+png8_filmic", shipped={"partial": 0.3,
                                                             "quantised_share": 0.2}),
        _generator_run(tmp_path, "blenderproc", "denoise", rng, {"denoise": True},
                       chain="denoise+png8_filmic",
                       shipped={"partial": math.nan, "quantised_share": 0.97}),
    ]
    outputs = {fmt: str(tmp_path / f"generators.{fmt}") for fmt in ("csv", "md")}
    generators_table_job(runs, outputs)
    rows = {r["profile"]: r for r in read_rows(outputs["csv"]) if r["region"] == "all"}
    kubric = rows["kubric"]
    assert kubric["output"] == "8-bit PNG, Filmic" and kubric["shipped_mc_cue"] == "remains"
    assert 0.2 < kubric["shipped_mc_specific_low"] < 0.3 < kubric["shipped_mc_specific_high"]
    assert abs(kubric["shipped_null_partial"]) < 0.05
    assert rows["blenderproc"]["shipped_mc_cue"] == "not testable"
    assert rows["blenderproc"]["quantised_share"] == pytest.approx(0.97)
    assert rows["paper"]["output"] == "float (EXR)" and rows["paper"]["shipped_mc_cue"] == "n/a"
    text = (tmp_path / "generators.md").read_text()
    assert "undefined: the codes fix the variance at 97% of pixels" in text
