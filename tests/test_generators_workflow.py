"""`snakemake generators` end to end on a tiny run: every profile rendered by Cycles with the
settings it declares, measured against its own matched null."""

from __future__ import annotations

import copy
import json
import math

import pytest

pytestmark = pytest.mark.workflow


def test_the_generators_target_end_to_end(tmp_path):
    """A dry run writes nothing; the renders record each profile's Cycles settings; the table
    has every profile; one seed shared by two separate renders couples the views, multiview
    and per-view seeds do not; a denoiser raises the PSNR."""
    pytest.importorskip("bpy")
    from stereovar.io.store import open_dataset
    from stereovar.io.tables import read_rows

    from .test_workflow import TINY, copy_workflow, snakemake

    config = copy.deepcopy(TINY)
    config["scenes"] = ["scene_000"]
    config["render"].update({"n_seeds": 4, "seeds_per_job": 4})
    config["generators"] = {"scenes": ["scene_000"], "spp": 8, "denoised_replicates": 1}
    root = copy_workflow(tmp_path / "wf", config)
    before = sorted(p.relative_to(root) for p in root.rglob("*") if ".snakemake" not in p.parts)
    dry = snakemake(root, "-n", "generators")
    assert dry.stdout.count("rule render_profile:") == 3
    assert sorted(
        p.relative_to(root) for p in root.rglob("*") if ".snakemake" not in p.parts
    ) == before
    snakemake(root, "-j2", "generators")

    def store(profile, view):
        key = "cycles" if profile == "paper" else f"cycles/{profile}"
        return open_dataset(root / f"results/{key}/renders/scene_000/{view}/spp8/seeds0-3.zarr")

    def settings(profile):
        return json.loads(store(profile, "left").attrs["renderer_options"])

    kubric, bproc, infinigen = (settings(p) for p in ("kubric", "blenderproc", "infinigen"))
    assert kubric["denoise"] and kubric["denoiser"] == "render"
    assert bproc["denoiser"] == "compositor" and bproc["multiview"]
    # scaled from 1024 (blenderproc) and 8192 (infinigen) to 8 SPP: the threshold rises
    assert bproc["adaptive_sampling"] and infinigen["adaptive_sampling"]
    assert math.isclose(infinigen["adaptive_threshold"], 0.01 * math.sqrt(1024))
    assert not infinigen["denoise"]
    # the seed each view was given: one per render for the shared rules, else one per view
    for profile, shared in (("paper", False), ("kubric", True), ("infinigen", True)):
        seeds = [store(profile, v)["sampler_seed"].values.tolist() for v in ("left", "right")]
        assert (seeds[0] == seeds[1]) is shared, profile

    rows = {r["profile"]: r for r in read_rows(root / "results/tables/generators.csv")
            if r["region"] == "all"}
    assert list(rows) == ["paper", "kubric", "blenderproc", "infinigen"]
    assert rows["kubric"]["spp_scale"] == 8 / 128 and rows["kubric"]["generator_spp"] == 128
    coupling = {p: (r["residual_rho_zero_low"], r["residual_rho_zero_high"])
                for p, r in rows.items()}
    for coupled in ("kubric", "infinigen"):
        for free in ("paper", "blenderproc"):
            assert coupling[coupled][0] > coupling[free][1], (coupled, free)
    assert rows["kubric"]["psnr"] > rows["paper"]["psnr"]
    # the denoising profiles are measured against a null passed through the denoiser
    assert rows["kubric"]["null_partial"] > rows["paper"]["null_partial"]
    assert all(math.isfinite(r["mc_specific"]) for r in rows.values())
    # each verdict's calibration is kept beside the table
    kept = read_rows(root / "results/tables/generators_calibration.csv")
    assert {r["profile"] for r in kept} == set(rows)
