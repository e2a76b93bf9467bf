"""Multi-seed renders: distinct per-view seeds, reproducibility, independent residuals."""

import numpy as np
import pytest
from scipy.stats import spearmanr

from stereovar.experiment import VIEWS, render_stores, seed_batches
from stereovar.io.store import open_dataset
from stereovar.jobs.render import render_job
from stereovar.renderers.mitsuba.render import render_view
from stereovar.renderers.mitsuba.scene import load_scene
from stereovar.rig import make_rig
from stereovar.scenes.spec import load_scene_spec
from stereovar.seeding import derive_seed, render_seed

from .test_ground_truth import REPO

RIG = {"width": 48, "height": 27, "baseline_m": 0.026, "convention": "paper"}


def test_seeds_differ_between_views_and_are_deterministic():
    seeds = {
        (view, spp, n): derive_seed("scene_000", view, spp, n)
        for view in VIEWS
        for spp in (16, 32)
        for n in range(30)
    }
    assert len(set(seeds.values())) == len(seeds)
    assert all(0 <= s < 2**32 for s in seeds.values())
    assert derive_seed("scene_000", "left", 16, 3) == seeds[("left", 16, 3)]


def test_seed_batches_are_aligned_and_cover_every_seed():
    assert seed_batches(5, 2) == [[0, 1], [2, 3], [4]]
    # Growing N by a multiple of the batch size keeps the existing batches unchanged.
    assert seed_batches(8, 4)[:1] == seed_batches(4, 4)
    for n, size in ((1, 1), (7, 3), (30, 8)):
        flat = [s for batch in seed_batches(n, size) for s in batch]
        assert flat == list(range(n))


def test_render_store_list_matches_config():
    config = {
        "scenes": ["a", "b"],
        "render": {
            "renderer": "mitsuba",
            "spp": 4,
            "n_seeds": 3,
            "seeds_per_job": 2,
            "spp_sweep": {"scene": "a", "spp": [2, 4]},
        },
    }
    stores = render_stores(config)
    assert len(stores) == 3 * 2 * 2  # (scene, spp) pairs x views x seed batches
    assert "results/mitsuba/renders/a/right/spp2/seeds0-1.zarr" in stores
    assert "results/mitsuba/renders/a/right/spp2/seeds2-2.zarr" in stores
    assert not any("/b/" in s and "spp2" in s for s in stores)


def test_batch_labels_round_trip():
    from stereovar.experiment import batch_label, batch_seeds

    for batch in seed_batches(11, 4):
        assert batch_seeds(batch_label(batch)) == batch
    with pytest.raises(ValueError):
        batch_label([0, 2])
    with pytest.raises(ValueError):
        batch_seeds("3-1")


def test_independent_policy_is_the_labelled_seed():
    for view in VIEWS:
        assert render_seed("s", view, 8, 3) == derive_seed("s", view, 8, 3)
    from stereovar.errors import ConfigError

    with pytest.raises(ConfigError, match="render.seed_policy.*use one of: independent, shared"):
        render_seed("s", "left", 8, 3, policy="bogus")


def test_shared_policy_gives_both_views_one_seed_apart_from_independent_ones():
    seeds = {v: render_seed("s", v, 8, 3, policy="shared") for v in VIEWS}
    assert seeds["left"] == seeds["right"] == derive_seed("shared", "s", 8, 3)
    assert seeds["left"] not in {derive_seed("s", v, 8, 3) for v in VIEWS}
    assert render_seed("s", "left", 8, 4, policy="shared") != seeds["left"]


def test_render_job_is_bit_identical_and_records_provenance(mi, tmp_path):
    spec = REPO / "scenes/scene_001.yaml"
    runs = []
    for k in range(2):
        outs = {v: tmp_path / f"run{k}_{v}.zarr" for v in VIEWS}
        render_job(spec, outs, seeds=[0, 1], spp=2, **RIG)
        runs.append([open_dataset(outs[v]) for v in VIEWS])
    for a, b in zip(*runs, strict=True):
        np.testing.assert_array_equal(a["radiance"].values, b["radiance"].values)
    left, right = runs[0]
    assert [str(ds["view"].values) for ds in runs[0]] == list(VIEWS)
    for view, ds in zip(VIEWS, runs[0], strict=True):
        assert ds["seed"].values.tolist() == [0, 1]
        assert ds["sampler_seed"].values.tolist() == [
            derive_seed("scene_001", view, 2, n) for n in (0, 1)
        ]
        assert ds["n_nonfinite_pixels"].values.tolist() == [0, 0]
    attrs = left.attrs
    assert attrs["rfilter"] == "box" and attrs["sampler"] == "independent"
    assert attrs["renderer"] == "mitsuba" and len(attrs["scene_digest"]) == 64
    assert attrs["seed_policy"] == "independent" and len(attrs["config_digest"]) == 64
    assert left["radiance"].dims == ("seed", "y", "x", "channel")
    assert left["radiance"].attrs["units"] == "W m-2 sr-1"
    assert left["x"].attrs["units"] == "px" and left["y"].values.tolist() == list(range(27))
    assert not np.array_equal(left["radiance"].values[0], right["radiance"].values[0])
    assert not np.array_equal(left["radiance"].values[0], left["radiance"].values[1])


def test_render_job_rejects_mismatched_outputs(tmp_path):
    from stereovar.errors import StereovarError

    with pytest.raises(StereovarError, match="output per view"):
        render_job(
            REPO / "scenes/scene_001.yaml",
            {"left": tmp_path / "a.zarr"},
            seeds=[0, 1],
            spp=1,
            **RIG,
        )


def residuals(stack):
    return stack - stack.mean(axis=0, keepdims=True)


def test_left_right_residuals_are_uncorrelated_at_zero_disparity(mi):
    """Distinct per-view seeds give independent noise; shared seeds would not (control)."""
    spec = load_scene_spec(REPO / "scenes/scene_002.yaml")
    scene, cam = load_scene(mi, spec)
    rig = make_rig(cam.to_world, cam.fov_deg, **RIG)
    n_seeds, spp = 6, 2

    def stack(view, seed_view):
        return np.stack(
            [
                render_view(
                    mi, scene, rig, view, spp=spp, seed=derive_seed(spec["name"], seed_view, spp, n)
                ).mean(axis=-1)
                for n in range(n_seeds)
            ]
        )

    left = residuals(stack("left", "left"))
    right = residuals(stack("right", "right"))
    shared = residuals(stack("right", "left"))  # the right view with the left view's seeds
    n = left.size
    # Rank correlation: a few fireflies would dominate Pearson at 2 spp.
    rho = spearmanr(left.ravel(), right.ravel())[0]
    rho_shared = spearmanr(left.ravel(), shared.ravel())[0]
    # Residuals sum to zero over seeds, so n (n_seeds - 1) / n_seeds are free; 5 sigma.
    assert abs(rho) < 5 / np.sqrt(n * (n_seeds - 1) / n_seeds)
    assert rho_shared > 0.3


def test_scene_loads_are_deterministic(mi):
    """Shapes and emitters keep one order across loads, so a seed always draws the same
    light choices (parallel loading or shape merging would shuffle them)."""
    spec = load_scene_spec(REPO / "scenes/scene_001.yaml")
    orders = {tuple(s.id() for s in load_scene(mi, spec)[0].shapes()) for _ in range(4)}
    assert len(orders) == 1
    order = next(iter(orders))
    assert "" not in order  # no merged, anonymous shapes
    assert {f"obj_{o['name']}" for o in spec["objects"]} <= set(order)
