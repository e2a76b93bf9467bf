"""The logic behind the workflow's input functions, params and cluster requests
(:mod:`stereovar.workflow_inputs`), tested as plain Python: no Snakemake run."""

from __future__ import annotations

import shlex
from pathlib import Path
from types import SimpleNamespace

import pytest
import yaml

from stereovar import resources as sizing
from stereovar.workflow_inputs import mitigations, resources, run, scenes

W, H = 64, 36
CLUSTER = {
    "render_samples_per_second": 2.0e5,
    "render_threads": 3,
    "gpus_per_render": 0,
    "gpu_model": None,
}


def evaluate(requests: dict, wildcards, attempt: int) -> dict:
    """Each request's value for a job, as Snakemake evaluates a callable request."""
    return {
        k: v(wildcards, attempt) if callable(v) else v for k, v in requests.items()
    }


# --- cluster requests -----------------------------------------------------------------------


def test_a_render_request_follows_the_jobs_batch_spp_and_attempt():
    job = SimpleNamespace(batch="4-7", spp="16")  # seeds 4..7: 4 per view
    got = evaluate(resources.render_resources(W, H, CLUSTER), job, attempt=2)
    assert got == {
        "mem_mb": sizing.render_mem_mb(W, H, batch=4, attempt=2),
        "runtime": sizing.render_runtime(
            W, H, 16, 2 * 4, samples_per_second=2.0e5, attempt=2
        ),
        "cpus_per_task": 3,
    }
    # a fixed SPP, one view, no batch wildcard (one seed), the job's own CPUs
    fixed = resources.render_resources(W, H, CLUSTER, n_views=1, spp=128, cpus=1)
    got = evaluate(fixed, SimpleNamespace(), attempt=1)
    assert got["runtime"] == sizing.render_runtime(W, H, 128, 1, samples_per_second=2.0e5)
    assert got["mem_mb"] == sizing.render_mem_mb(W, H, batch=1)
    assert got["cpus_per_task"] == 1


def test_a_moments_render_asks_for_the_moments_memory():
    got = evaluate(
        resources.render_resources(W, H, CLUSTER, moments=True), SimpleNamespace(spp="8"), 3
    )
    assert got["mem_mb"] == sizing.moments_mem_mb(W, H, attempt=3)


def test_gpus_are_asked_for_only_where_the_cluster_gives_renders_gpus():
    assert "gpu" not in resources.render_resources(W, H, CLUSTER)
    gpus = {**CLUSTER, "gpus_per_render": 1}
    assert resources.render_resources(W, H, gpus)["gpu"] == 1
    assert "gpu_model" not in resources.render_resources(W, H, gpus)
    model = resources.render_resources(W, H, {**gpus, "gpu_model": "a100"})
    assert (model["gpu"], model["gpu_model"]) == (1, "a100")
    assert "gpu" not in resources.render_resources(W, H, gpus, gpu=False)


@pytest.mark.parametrize(
    "width, given, expected",
    [(320, None, 16 + 2), (321, None, 17 + 2), (320, 40, 40)],  # ceil(0.05 W) + margin 2
)
def test_the_intervention_is_sized_for_the_configured_or_estimated_disparity(
    width, given, expected
):
    intervention = {"max_disparity": given, "disparity_margin": 2}
    assert resources.intervention_disparity(width, intervention) == expected
    got = evaluate(
        resources.intervention_resources(width, H, intervention, n_seeds=6), None, 1
    )
    assert got["runtime"] == sizing.intervention_runtime(width, H, 6, expected + 1)
    assert got["cpus_per_task"] == 2


def test_the_calibration_counts_its_denoisers_apart():
    cal = {"replicates": 4, "strengths": [0.5, 1.0, 2.0], "denoised_replicates": 1}
    # none and equalise run every replicate; denoise (OIDN) only the denoised ones
    transforms = ["none", "denoise", "equalise"]
    got = evaluate(resources.calibration_resources(W, H, cal, 5, transforms), None, 1)
    assert got["runtime"] == sizing.calibration_runtime(
        W, H, 5, replicates=4, designs=2 + 3, transforms=2, denoised_replicates=1, denoisers=1
    )
    assert got["mem_mb"] == sizing.analysis_mem_mb(W, H, 4 * 5 + 16)


# --- scenes ---------------------------------------------------------------------------------


def test_missing_specs_split_into_generatable_and_unknown(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "scenes").mkdir()
    (tmp_path / "scenes" / "scene_000.yaml").write_text("{}")
    listed = ["scene_000", "scene_001", "scene_01", "kitchen"]
    assert scenes.missing_scene_specs(listed) == (["scene_001"], ["scene_01", "kitchen"])
    assert scenes.missing_scene_specs(listed, audit=True) == ([], [])


def test_an_xml_scene_reads_its_mitsuba_file_and_what_that_reads(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "scenes").mkdir()
    (tmp_path / "scenes" / "room.yaml").write_text("mitsuba_xml: xml/room.xml\n")
    (tmp_path / "scenes" / "plain.yaml").write_text("seed: 3\n")
    asked = []

    def references(xml):
        asked.append(Path(xml))
        return [Path(xml).parent / "mesh.ply"]

    assert scenes.scene_inputs("room", references) == {
        "spec": "scenes/room.yaml",
        "xml": "scenes/xml/room.xml",
        "xml_files": ["scenes/xml/mesh.ply"],
    }
    assert asked == [Path("scenes/xml/room.xml")]
    assert scenes.scene_inputs("plain", references) == {"spec": "scenes/plain.yaml"}
    assert scenes.scene_inputs("absent", references) == {"spec": "scenes/absent.yaml"}
    assert len(asked) == 1


# --- mitigations ----------------------------------------------------------------------------


def test_aux_passes_are_read_only_where_the_source_renders_them():
    assert mitigations.reads_aux(["denoise"], "mitsuba")  # albedo and normal: Mitsuba has both
    assert not mitigations.reads_aux(["denoise"], "cycles")  # Cycles renders no aux pass
    assert not mitigations.reads_aux(["denoise"], "audit/mine")
    assert not mitigations.reads_aux(["equalise", "sensor_only"], "mitsuba")  # none wanted
    assert mitigations.reads_aux(["equalise", "denoise_sensor"], "mitsuba")
    assert not mitigations.reads_aux([], "mitsuba")


def test_the_reference_is_a_moments_render_only_for_a_moments_renderer_with_its_settings():
    moments = {"sampler": "independent", "rfilter": "box"}
    assert mitigations.reference_from_moments("mitsuba", moments)
    assert not mitigations.reference_from_moments("mitsuba", {**moments, "sampler": "stratified"})
    assert not mitigations.reference_from_moments("cycles", moments)
    assert not mitigations.reference_from_moments("audit/mine", moments)


def test_a_transform_gets_the_camera_model_only_when_it_takes_it():
    sensor = {"gain": 1000, "read_noise": 2.0, "seed": 0}
    assert mitigations.transform_options("sensor_only", sensor) == {
        "gain": 1000,
        "read_noise": 2.0,
    }
    assert mitigations.transform_options("denoise", sensor) == {}


@pytest.mark.parametrize(
    "kind, transform, source, expected",
    [
        ("transform", "equalise", "mitsuba", {"render_spp": 16 * 5, "aux_spp": 0}),  # seed mean
        ("transform", "denoise", "mitsuba", {"render_spp": 16, "aux_spp": 8}),  # one aux pass
        ("transform", "denoise", "cycles", {"render_spp": 16, "aux_spp": 0}),
        ("seed_policy", "none", "mitsuba", {"render_spp": 16, "aux_spp": 0}),
    ],
)
def test_the_cost_of_a_mitigated_image(kind, transform, source, expected):
    row = SimpleNamespace(
        spp=16, transform=transform, source=source, mitigation=SimpleNamespace(kind=kind)
    )
    assert mitigations.image_cost(row, n_seeds=5, aux_spp=8) == expected


# --- the run --------------------------------------------------------------------------------


def test_the_rebuild_arguments_give_back_the_runs_config_files_and_overrides():
    files = ["a b.yaml", "it's.yaml"]
    overrides = {"render": {"spp": 4, "renderer": "cycles"}, "scenes": ["s 1", "s:2"]}
    words = shlex.split(run.snakemake_arguments(files, overrides))
    assert words[:4] == ["--configfile", "a b.yaml", "--configfile", "it's.yaml"]
    assert words[4] == "--config"
    parsed = {}
    for entry in words[5:]:
        key, value = entry.split("=", 1)
        parsed[key] = yaml.safe_load(value)
    assert parsed == overrides
    assert run.snakemake_arguments([], None) == run.snakemake_arguments([], {}) == ""


def test_the_results_page_shows_figures_and_tables_of_all_but_its_own():
    targets = [
        "results/figures/fig1.png",
        "results/figures/fig1.pdf",
        "results/mitsuba/seeds/figures/probe.png",
        "results/tables/claims.md",
        "results/tables/claims.json",
        "results/mitsuba/renders/s.zarr",
        "results/index.html",
    ]
    own = {"results/mitsuba/seeds/figures/probe.png", "results/index.html"}
    assert run.page_results(targets, own, ("csv", "md")) == (
        ["results/figures/fig1.png"],
        ["results/tables/claims.md"],
    )
    assert len(run.page_results(targets, set(), ("md",))[0]) == 2  # its own figures too
