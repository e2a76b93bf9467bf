"""Workflow config: schema defaults, one-line errors, shipped configs and profile."""

from __future__ import annotations

import copy
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from stereovar.config import load_config, merge_configs, validate_config, validate_config_or_exit
from stereovar.errors import ConfigError

REPO_ROOT = Path(__file__).resolve().parents[1]
SCHEMA = REPO_ROOT / "workflow" / "schemas" / "config.schema.yaml"
CONFIG = REPO_ROOT / "config.yaml"
PAPER = REPO_ROOT / "workflow" / "presets" / "paper.yaml"

DEFAULTS = {
    "scenes": ["scene_000", "scene_001", "scene_002", "scene_003"],
    "generator": {"seed": 0},
    "resolution": {"width": 320, "height": 180},
    "rig": {"baseline_m": 0.026, "convention": "paper"},
    "render": {
        "renderer": "mitsuba",
        "cycles": {
            "denoise": False,
            "denoiser": "render",
            "denoising_input_passes": "RGB_ALBEDO_NORMAL",
            "adaptive_sampling": False,
            "adaptive_threshold": 0.01,
            "adaptive_min_samples": 0,
            "multiview": False,
            "seed": "per_view",
            "view_transform": "Standard",
            "light_tree": False,
            "clamp_direct": 0,
            "clamp_indirect": 0,
            "sampling_pattern": "TABULATED_SOBOL",
        },
        "estimator": "seeds",
        "seed_policy": "independent",
        "variant": "auto",
        "allow_mixed_backends": False,
        "cache": "cache/renders",
        "integrator": "path",
        "max_depth": 8,
        "rfilter": "box",
        "sampler": "independent",
        "spp": 32,
        "n_seeds": 8,
        "seeds_per_job": 8,
        "spp_sweep": {"scene": "scene_000", "spp": [8, 16, 32, 64, 128]},
    },
    "analysis": {
        "min_pixels": 30,
        "trim_fraction": 0.001,
        "firefly_factor": 100,
        "bootstrap": {"tile": 16, "reps": 1000, "seed": 0},
    },
    "controls": {"null_shift": 8, "sensor": {"gain": 1000, "read_noise": 2, "seed": 0}},
    "intervention": {
        "window": 5,
        "block": 16,
        "seed": 0,
        "max_disparity": None,
        "disparity_margin": 4,
        "margin_samples": 2000,
        "n_seeds": None,
        "spp": None,
    },
    "cluster": {
        "render_samples_per_second": 1.0e6,
        "render_threads": 2,
        "gpus_per_render": 0,
        "gpu_model": None,
        "max_mem_mb": None,
    },
    "preview": {"spp": 32},
    "calibration": {
        "replicates": 16,
        "denoised_replicates": 2,
        "strengths": [0.0625, 0.125, 0.25, 1.0, 2.0],
        "pipelines": ["shading", "gain_map", "srgb8_0.2", "srgb8_0.4", "srgb8_1",
                      "white_balance", "colour_matrix", "power_law", "correlated"],
        "pipeline_replicates": 5,
        "seed": 0,
    },
    "validation": {"n_seeds": 64, "spp": None},
    "export": {"formats": ["exr"]},
    "mitigations": {
        "names": ["shared_seed", "spp_x4", "denoise", "denoise_sensor", "equalise", "sensor_only"],
        "reference_spp": 128,
        "aux_spp": 16,
        "seed": 0,
        "dose_response": {
            "transforms": None,
            "gains": [100, 30],
            "multiples": [1, 2, 4, 8, 16, 32, 64],
            "replicates": 2,
        },
    },
    "generators": {
        "profiles": ["kubric", "blenderproc", "infinigen"],
        "scenes": None,
        "spp": 64,
        "denoised_replicates": 4,
    },
    "probe": {
        "conditions": ["none", "sensor_only"],
        "planted": [1],
        "planted_series": {},
        "mitigations": ["denoise"],
        "architectures": ["mccnn", "costvolume"],
        "folds": 2,
        "train_seeds": 3,
        "test_frames": 1,
        "validation_rows": 64,
        "strata": 64,
        "conflict_shift": 3,
        "seed": 0,
        "device": "cpu",
        "training": {
            "steps": 400,
            "check_every": 50,
            "patience": 2,
            "min_delta": 0.002,
            "min_steps": 100,
            "crops": 4,
            "crop_rows": 16,
            "crop_cols": 64,
            "pos": 0.5,
            "neg_low": 1.5,
            "neg_high": 6.0,
            "margin": 0.2,
            "optimiser": "adam",
            "learning_rate": 0.001,
            "momentum": 0.9,
            "threads": 1,
        },
        "costvolume": {
            "steps": 400,
            "check_every": 50,
            "patience": 2,
            "min_delta": 0.002,
            "min_steps": 100,
            "crops": 4,
            "crop_rows": 32,
            "crop_cols": 96,
            "learning_rate": 0.001,
            "beta": 1.0,
            "threads": 1,
            "max_disparity": None,
            "disparity_margin": 4,
            "scale": 4,
            "features": 16,
        },
    },
}


def test_empty_config_gets_every_default():
    assert validate_config({}, SCHEMA) == DEFAULTS
    assert validate_config(None, SCHEMA) == DEFAULTS


def test_partial_config_keeps_values_and_fills_the_rest():
    given = {
        "render": {"spp": 32, "spp_sweep": {"spp": [32]}},
        "rig": {"convention": "conventional"},
    }
    original = copy.deepcopy(given)
    out = validate_config(given, SCHEMA)
    assert given == original, "the input must not be modified"
    assert out["render"]["spp"] == 32 and out["render"]["n_seeds"] == 8
    assert out["render"]["spp_sweep"] == {"scene": "scene_000", "spp": [32]}
    assert out["rig"] == {"baseline_m": 0.026, "convention": "conventional"}
    assert out["preview"] == {"spp": 32}


def test_defaults_are_not_shared_between_calls():
    first = validate_config({}, SCHEMA)
    first["scenes"].append("scene_999")
    assert validate_config({}, SCHEMA)["scenes"] == DEFAULTS["scenes"]


def test_max_depth_accepts_minus_one():
    assert validate_config({"render": {"max_depth": -1}}, SCHEMA)["render"]["max_depth"] == -1


BAD_CONFIGS = [
    pytest.param(
        {"colour": "red"},
        [
            "'colour'",
            "not known",
            "scenes, generator, resolution, rig, renderers, render, analysis, controls, "
            "calibration, validation, export, audit, intervention, cluster, preview",
        ],
        id="unknown-top-level-key",
    ),
    pytest.param(
        {"render": {"sppp": 8}},
        ["'render.sppp'", "not known", "under 'render'", "spp, n_seeds, seeds_per_job, spp_sweep"],
        id="unknown-nested-key",
    ),
    pytest.param(
        {"resolution": {"width": "320"}},
        ["'resolution.width'", "expected an integer", "'320'", "a string"],
        id="wrong-type",
    ),
    pytest.param(
        {"render": {"spp": 64.0}},
        ["'render.spp'", "expected an integer", "64.0"],
        id="float-for-integer",
    ),
    pytest.param(
        {"rig": {"convention": "left"}},
        ["config key 'rig.convention': 'left' is not allowed; use one of: paper, conventional"],
        id="bad-enum",
    ),
    pytest.param(
        {"render": {"variant": "gpu"}},
        ["'render.variant'", "auto, cuda_ad_rgb, llvm_ad_rgb, scalar_rgb"],
        id="bad-variant",
    ),
    pytest.param(
        {"render": {"n_seeds": 1}},
        ["'render.n_seeds'", "1 is too small", ">= 2"],
        id="one-seed",
    ),
    pytest.param(
        {"render": {"spp": 256}},
        ["'render.spp_sweep.spp'", "render.spp = 256", "add 256", "16, 32, 64, 128"],
        id="sweep-without-main-spp",
    ),
    pytest.param(
        {"render": {"spp_sweep": {"scene": "scene_007"}}},
        ["'render.spp_sweep.scene'", "'scene_007'", "not in scenes", "scene_000, scene_001"],
        id="sweep-scene-not-in-scenes",
    ),
    pytest.param(
        {"scenes": ["scene_000", "scene_000"]},
        ["'scenes'", "'scene_000' listed more than once"],
        id="duplicate-scene",
    ),
    pytest.param(
        {"scenes": ["my scene"]},
        ["'scenes[0]'", "'my scene'", "letters, digits"],
        id="bad-scene-name",
    ),
    pytest.param({"scenes": []}, ["'scenes'", "at least 1 item"], id="no-scenes"),
    pytest.param(
        {"rig": {"baseline_m": 0}}, ["'rig.baseline_m'", "0 is too small", "> 0"], id="baseline"
    ),
    pytest.param(
        {"render": {"max_depth": 0}}, ["'render.max_depth'", "-1 for unbounded"], id="max-depth"
    ),
    pytest.param(
        {"resolution": [320, 180]},
        ["'resolution'", "expected a mapping", "[320, 180]"],
        id="list-for-mapping",
    ),
]


@pytest.mark.parametrize(("config", "expected"), BAD_CONFIGS)
def test_invalid_config_raises_one_line_error(config, expected):
    with pytest.raises(ConfigError) as info:
        validate_config(config, SCHEMA)
    message = str(info.value)
    assert "\n" not in message
    for part in expected:
        assert part in message, f"{part!r} missing from: {message}"


def test_several_problems_are_counted_on_the_same_line():
    with pytest.raises(ConfigError, match=r"and 1 more problem\)$"):
        validate_config({"render": {"spp": 0, "n_seeds": 0}}, SCHEMA)


def test_validate_config_or_exit_exits_with_the_message():
    with pytest.raises(SystemExit) as info:
        validate_config_or_exit({"rig": {"convention": "left"}}, SCHEMA)
    assert str(info.value.code).startswith("stereovar: config key 'rig.convention'")
    assert validate_config_or_exit({}, str(SCHEMA)) == DEFAULTS


def test_shipped_config_holds_the_schema_defaults():
    assert load_config(CONFIG, SCHEMA) == DEFAULTS


def test_paper_preset_merged_over_config_validates():
    config = load_config([CONFIG, PAPER], SCHEMA)
    assert config["scenes"] == [f"scene_{i:03d}" for i in range(20)]
    assert config["resolution"] == {"width": 1280, "height": 720}
    assert config["rig"] == {"baseline_m": 0.026, "convention": "paper"}
    render = config["render"]
    assert (render["spp"], render["n_seeds"]) == (512, 30)
    assert render["spp_sweep"] == {"scene": "scene_000", "spp": [128, 256, 512, 1024, 2048]}
    assert render["rfilter"] == "box" and render["variant"] == "auto"
    assert config["preview"] == {"spp": 64}


def test_merge_configs_merges_mappings_and_replaces_lists():
    base = {"a": {"b": 1, "c": [1, 2]}, "d": 1}
    merged = merge_configs(base, {"a": {"c": [3]}, "e": 2})
    assert merged == {"a": {"b": 1, "c": [3]}, "d": 1, "e": 2}
    assert base == {"a": {"b": 1, "c": [1, 2]}, "d": 1}


def test_load_config_names_a_missing_file(tmp_path):
    missing = tmp_path / "nope.yaml"
    with pytest.raises(ConfigError, match=re.escape(str(missing))):
        load_config(missing, SCHEMA)


def test_load_config_names_an_unparsable_file(tmp_path):
    broken = tmp_path / "broken.yaml"
    broken.write_text("render: {spp: [1, 2\n")
    with pytest.raises(ConfigError) as info:
        load_config(broken, SCHEMA)
    assert str(broken) in str(info.value) and "not valid YAML" in str(info.value)
    assert "\n" not in str(info.value)


def test_schema_works_with_snakemake_validate():
    from snakemake.utils import validate

    config: dict = {}
    validate(config, str(SCHEMA), set_default=True)
    assert config == DEFAULTS
    validate(validate_config({}, SCHEMA), str(SCHEMA), set_default=True)


def test_schema_forbids_unknown_keys_everywhere():
    schema = yaml.safe_load(SCHEMA.read_text())

    def objects(node, path="config"):
        if isinstance(node, dict):
            if node.get("type") == "object":
                yield path, node
            for key, value in node.get("properties", {}).items():
                yield from objects(value, f"{path}.{key}")

    for path, node in objects(schema):
        assert node.get("additionalProperties") is False, path
        # `audit` is absent unless a run audits renders made elsewhere: no default
        assert path in ("config", "config.audit") or "default" in node, path


def test_default_profile_uses_only_known_snakemake_options():
    profile = yaml.safe_load((REPO_ROOT / "profiles" / "default" / "config.yaml").read_text())
    help_text = subprocess.run(
        [sys.executable, "-m", "snakemake", "--help"],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    ).stdout
    unknown = [key for key in profile if f"--{key}" not in help_text]
    assert not unknown, f"not snakemake options: {unknown}"


def test_conda_env_pins_match_pyproject():
    tomllib = pytest.importorskip("tomllib")
    project = tomllib.loads((REPO_ROOT / "pyproject.toml").read_text())["project"]
    env = yaml.safe_load((REPO_ROOT / "envs" / "stereovar.yaml").read_text())
    pip = next(item["pip"] for item in env["dependencies"] if isinstance(item, dict))
    # the env is Python 3.11, so it carries the cycles extra too (without its marker), and
    # the mitigations extra that the default run needs, and the probe's PyTorch
    extras = [
        r.split(";")[0].strip()
        for extra in ("cycles", "mitigations", "probe")
        for r in project["optional-dependencies"][extra]
    ]
    assert sorted(pip) == sorted(project["dependencies"] + extras)
    assert "python=3.11" in env["dependencies"]
    # and this environment, set up from pyproject.toml, satisfies every pin
    from importlib.metadata import version

    from packaging.requirements import Requirement

    for req in map(Requirement, pip):
        assert req.specifier.contains(version(req.name), prereleases=True), req


@pytest.mark.parametrize(
    ("override", "needles"),
    [
        ({"intervention": {"window": 4}}, ["'intervention.window'", "even", "5"]),
        ({"intervention": {"window": 0}}, ["'intervention.window'"]),
        ({"intervention": {"block": 200}}, ["'intervention.block'", "320x180", "180"]),
        ({"intervention": {"window": 181}}, ["'intervention.window'", "320x180", "at most 179"]),
        (
            {"resolution": {"width": 48, "height": 27}, "intervention": {"window": 999}},
            ["'intervention.window'", "999 is larger than the image (48x27)", "at most 27"],
        ),
    ],
)
def test_intervention_settings_are_checked(override, needles):
    with pytest.raises(ConfigError) as err:
        validate_config(override, SCHEMA)
    message = str(err.value)
    assert "\n" not in message
    for needle in needles:
        assert needle in message


def test_the_largest_window_accepted_is_the_largest_that_scores_a_pixel():
    # A SAD window scores a pixel only where it lies inside the image, so on 48x27 a side
    # of 27 scores one row and 29 nothing: every Table 3 row would be NaN.
    from stereovar.intervention.scan import disparity_slices

    field = np.random.default_rng(0).random((27, 48))
    scored = {
        window: sum(
            block.size
            for _, block, _ in disparity_slices(field, field, max_disparity=4, window=window)
        )
        for window in (27, 29)
    }
    assert scored[27] > 0 and scored[29] == 0
    small = {"resolution": {"width": 48, "height": 27}}
    assert validate_config({**small, "intervention": {"window": 27}}, SCHEMA)
    with pytest.raises(ConfigError, match=r"intervention\.window': 29 .* at most 27"):
        validate_config({**small, "intervention": {"window": 29}}, SCHEMA)


def test_command_line_strings_become_the_scalars_the_schema_asks_for():
    # `snakemake --config cluster={gpus_per_render: 1, gpu_model: null}` passes strings.
    given = {
        "cluster": {"gpus_per_render": "1", "gpu_model": "null", "render_threads": "4"},
        "render": {"spp": "16", "spp_sweep": {"spp": [16]}},
        "intervention": {"max_disparity": "~"},
    }
    config = validate_config(copy.deepcopy(given), SCHEMA, command_line=given)
    assert config["cluster"]["gpus_per_render"] == 1
    assert config["cluster"]["gpu_model"] is None
    assert config["cluster"]["render_threads"] == 4
    assert config["render"]["spp"] == 16
    assert config["intervention"]["max_disparity"] is None
    kept = validate_config({"cluster": {"gpu_model": "a100"}}, SCHEMA)
    assert kept["cluster"]["gpu_model"] == "a100"
    bad = {"cluster": {"gpus_per_render": "two"}}
    with pytest.raises(ConfigError, match="cluster.gpus_per_render"):
        validate_config(bad, SCHEMA, command_line=bad)
    # The same string in a config file (not given on the command line) stays an error.
    with pytest.raises(ConfigError, match="cluster.gpus_per_render"):
        validate_config({"cluster": {"gpus_per_render": "1"}}, SCHEMA)


def test_command_line_list_items_become_the_schema_item_type():
    # `snakemake --config 'render={spp: 16, spp_sweep: {spp: [4, 16]}}'` gives list items as
    # strings (Snakemake parses --config values with YAML's BaseLoader).
    given = {"render": {"spp": "16", "spp_sweep": {"spp": ["4", "16"]}}}
    config = validate_config(copy.deepcopy(given), SCHEMA, command_line=given)
    assert config["render"]["spp_sweep"]["spp"] == [4, 16]
    bad = {"render": {"spp": "16", "spp_sweep": {"spp": ["4", "many"]}}}
    with pytest.raises(ConfigError, match=r"render\.spp_sweep\.spp"):
        validate_config(copy.deepcopy(bad), SCHEMA, command_line=bad)
    # list items in a config file are not converted
    with pytest.raises(ConfigError, match=r"render\.spp_sweep\.spp"):
        validate_config({"render": {"spp": 16, "spp_sweep": {"spp": ["4", 16]}}}, SCHEMA)


def test_a_bootstrap_tile_larger_than_the_image_is_a_one_line_error():
    config = {"resolution": {"width": 64, "height": 32}, "analysis": {"bootstrap": {"tile": 40}}}
    with pytest.raises(ConfigError, match=r"analysis\.bootstrap\.tile.*at most 32"):
        validate_config(config, SCHEMA)


@pytest.mark.parametrize(
    ("render", "message"),
    [
        (
            {"sampler": "multijitter"},
            "'render.sampler': 'multijitter' with render.estimator moments",
        ),
        ({"rfilter": "tent"}, "'render.rfilter': 'tent' with render.estimator moments"),
        (
            {"spp": 8, "spp_sweep": {"scene": "scene_000", "spp": [2, 8]}},
            "'render.spp_sweep.spp': SPP 2 with render.estimator moments",
        ),
    ],
)
def test_moments_needs_independent_samples_in_their_own_pixel(render, message):
    config = {"render": {"estimator": "moments", **render}}
    with pytest.raises(ConfigError, match=re.escape(message)):
        validate_config(config, SCHEMA)
    assert validate_config({"render": {"estimator": "moments"}}, SCHEMA)["render"]["spp"] == 32


@pytest.mark.parametrize(
    "config",
    [
        {},
        {"audit": {"name": "a", "renders": "r/{view}/{seed}.exr"}},
        {"audit": {"name": "a", "renders": "r/{view}/{seed}.exr",
                   "probe_model": {"factory": "m:f", "weights": "w.pt"}}},
    ],
)
def test_snakemakes_own_default_filling_takes_every_config(config):
    """The workflow also runs Snakemake's `validate(..., set_default=True)`, which descends
    into every property's defaults: a nullable object must not declare defaults inside it."""
    from snakemake.utils import validate

    given = copy.deepcopy(config)
    validate(given, str(SCHEMA), set_default=True)
    assert given["probe"]["architectures"] == ["mccnn", "costvolume"]
