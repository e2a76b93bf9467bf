"""The moments estimator end to end: `all` and `estimators` on a tiny config."""

import copy
import shutil

import numpy as np
import pytest
from scipy import stats

from stereovar.io.store import open_dataset
from stereovar.io.tables import read_rows

from .test_workflow import SCENES, TINY, copy_workflow, snakemake

pytestmark = pytest.mark.workflow

MOMENTS = copy.deepcopy(TINY)
MOMENTS["render"].update(
    {"estimator": "moments", "spp": 8, "spp_sweep": {"scene": "scene_000", "spp": [4, 8]}}
)
MOMENTS["intervention"] = {"n_seeds": 2, "spp": 2}
MOMENTS["validation"] = {"n_seeds": 4, "spp": 8}
RUN = "results/mitsuba/moments"
RENDERS = "results/mitsuba/renders"


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    root = copy_workflow(tmp_path_factory.mktemp("moments"), MOMENTS)
    snakemake(root, "-j2", "all", "estimators")
    return root


def test_one_moment_store_per_scene_view_and_spp(workdir):
    for scene, spp in [(s, 8) for s in SCENES] + [("scene_000", 4)]:
        for view in ("left", "right"):
            ds = open_dataset(workdir / f"{RENDERS}/{scene}/{view}/spp{spp}/moments.zarr")
            assert ds.sizes["half"] == 2 and ds["half_spp"].values.sum() == spp
            assert ds.attrs["spp"] == spp and ds.attrs["estimator"] == "moments"
        v = open_dataset(workdir / f"{RUN}/variance/{scene}/spp{spp}.zarr")
        assert v.attrs["estimator"] == "moments" and v.attrs["n_draws"] == spp
        assert v.attrs["n_seeds"] == 2 and "half_variance" in v
    # seed renders only for the intervention (N = 2 at SPP 2) and the reference (N = 4)
    assert sorted(p.name for p in (workdir / RENDERS).glob("scene_001/left/spp*/seeds*.zarr")) == [
        "seeds0-1.zarr",
        "seeds0-1.zarr",
        "seeds2-3.zarr",
    ]
    for scene in SCENES:
        rows = read_rows(workdir / f"results/mitsuba/seeds/intervention/{scene}.csv")
        assert {int(r["n_seeds"]) for r in rows} == {2}
        assert {int(r["spp"]) for r in rows} == {2}


def test_tables_rows_carry_the_estimator_and_split_half_reliability(workdir):
    rows = read_rows(workdir / f"{RUN}/correlation/scene_000/spp8.csv")
    assert {r["estimator"] for r in rows} == {"moments"}
    warp = next(r for r in rows if (r["region"], r["method"]) == ("all", "warp"))
    assert np.isfinite(float(warp["reliability_left"]))
    curve = read_rows(workdir / f"{RUN}/correlation/scene_000/spp8_curve.csv")
    assert {int(r["n_prime"]) for r in curve} == {1, 2}
    assert (workdir / "results/tables/claims.md").is_file()


def brute_moment_field(path, spp):
    """The moment field of a moment store, straight from its arrays."""
    ds = open_dataset(path)
    n = ds["n_samples"].values.astype(np.float64)
    s1 = (ds["sample_mean"].values * n[..., None]).sum(axis=0)
    s2 = (ds["sample_mean_sq"].values * n[..., None]).sum(axis=0)
    total = n.sum(axis=0)[..., None]
    var = (s2 - s1 * s1 / total) / (total - 1)
    return var.mean(axis=-1) / spp


def brute_seed_field(paths):
    stack = np.concatenate([open_dataset(p)["radiance"].values for p in paths]).astype(np.float64)
    n = stack.shape[0]
    return stack.var(axis=0).mean(axis=-1) * n / (n - 1)


def test_estimator_fields_match_a_brute_force_recomputation(workdir):
    rows = read_rows(workdir / "results/tables/estimator_fields.csv")
    for scene in SCENES:
        for view in ("left", "right"):
            row = next(r for r in rows if (r["scene"], r["view"]) == (scene, view))
            moments = brute_moment_field(workdir / f"{RENDERS}/{scene}/{view}/spp8/moments.zarr", 8)
            seeds = brute_seed_field(
                sorted((workdir / f"{RENDERS}/{scene}/{view}/spp8").glob("seeds*.zarr"))
            )
            assert int(row["n_seeds_reference"]) == 4
            keep = np.isfinite(moments) & np.isfinite(seeds)
            assert int(row["n_pixels"]) == keep.sum()
            np.testing.assert_allclose(
                float(row["mean_ratio"]), moments[keep].sum() / seeds[keep].sum(), rtol=1e-4
            )
            assert float(row["ratio_low"]) <= float(row["mean_ratio"]) <= float(row["ratio_high"])
            np.testing.assert_allclose(
                float(row["spearman"]),
                stats.spearmanr(moments[keep], seeds[keep]).statistic,
                rtol=1e-4,
                atol=1e-6,
            )
            np.testing.assert_allclose(
                float(row["pearson"]), np.corrcoef(moments[keep], seeds[keep])[0, 1], rtol=1e-4
            )
    assert {r["scene"] for r in rows} == {*SCENES, "mean"}


def test_estimator_table_repeats_the_moments_run_rows(workdir):
    table = read_rows(workdir / "results/tables/estimators.csv")
    for scene in SCENES:
        native = read_rows(workdir / f"{RUN}/correlation/{scene}/spp8.csv")
        for r in native:
            row = next(
                t
                for t in table
                if (t["scene"], t["region"], t["method"]) == (scene, r["region"], r["method"])
            )
            np.testing.assert_allclose(
                float(row["moments_rho"]), float(r["rho"]), rtol=1e-12, equal_nan=True
            )
            np.testing.assert_allclose(
                float(row["moments_corrected"]),
                float(r["rho_corrected"]),
                rtol=1e-12,
                equal_nan=True,
            )
            bounds = [
                float(row[k])
                for k in (
                    "seeds_corrected_low",
                    "seeds_corrected_high",
                    "moments_corrected_low",
                    "moments_corrected_high",
                )
            ]
            agree = float(row["corrected_agree"])  # 1 or 0; NaN without corrected intervals
            if np.isfinite(bounds).all():
                overlap = max(bounds[0], bounds[2]) <= min(bounds[1], bounds[3])
                assert agree == float(overlap)
            else:
                assert np.isnan(agree)
    assert (workdir / "results/figures/estimators.png").read_bytes()[:4] == b"\x89PNG"
    assert "corrected" in (workdir / "results/tables/estimators.md").read_text()


def test_a_lost_moment_store_comes_back_from_the_render_cache(workdir):
    store = workdir / f"{RENDERS}/scene_001/left/spp8/moments.zarr"
    before = open_dataset(store)["sample_mean_sq"].values
    shutil.rmtree(store)
    snakemake(workdir, "-j2", "all")
    log = (workdir / "logs/mitsuba/renders/scene_001/left/spp8/moments.log").read_text()
    assert "0 rendered, 2 from the render cache" in log
    np.testing.assert_array_equal(open_dataset(store)["sample_mean_sq"].values, before)


@pytest.mark.parametrize(
    ("render", "message"),
    [
        ({"sampler": "stratified"}, "render.sampler.*moments"),
        ({"rfilter": "gaussian"}, "render.rfilter.*moments"),
        ({"spp": 2, "spp_sweep": {"scene": "scene_000", "spp": [2]}}, "render.spp.*4 or more"),
    ],
)
def test_moments_config_errors_stop_before_any_job(tmp_path, render, message):
    import re

    root = copy_workflow(tmp_path / "wf", MOMENTS)
    proc = snakemake(root, "-n", "all", config={"render": render}, check=False)
    assert proc.returncode != 0
    lines = [line for line in proc.stderr.splitlines() if line.startswith("stereovar:")]
    assert len(lines) == 1 and re.search(message, lines[0]), proc.stderr[-2000:]


def test_cluster_profiles_submit_one_render_job_per_scene_view_and_spp(workdir):
    import math

    from .test_workflow import job_resources

    for profile, gpus in (("profiles/slurm", None), ("profiles/slurm-gpu", "1")):
        proc = snakemake(workdir, "--profile", profile, "--executor", "dryrun", "all", "--forceall")
        jobs = job_resources(proc.stdout + proc.stderr)
        moments = jobs["render_moments"]
        assert len(moments) == 2 * 2 + 2  # (scene, view) at SPP 8, and the sweep's SPP 4
        assert all(r.get("gpu") == gpus for r in moments)
        # one view's film, two halves of moments and the store: 200 B per pixel
        assert {r["mem_mb"] for r in moments} == {str(1536 + math.ceil(200 * 48 * 27 / 2**20))}
        assert len(jobs["render"]) == 2  # the intervention's seeds, one batch per scene
