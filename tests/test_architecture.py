"""The seams: a renderer, an estimator, a statistic and a seed policy added from outside.

Each stub below is defined and registered in this file only; the jobs, the stored contracts
and the tables pick it up with no edit elsewhere. The stub renderer images a fronto-parallel
plane, so the ground truth and every downstream number have a known answer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
import xarray as xr
from scipy.stats import pearsonr, rankdata, spearmanr

from stereovar.errors import ConfigError
from stereovar.estimators import ESTIMATORS, get_estimator
from stereovar.estimators.base import VarianceEstimator
from stereovar.io.renders import RenderStore
from stereovar.io.store import open_dataset
from stereovar.renderers import RENDERERS, get_renderer
from stereovar.renderers.base import FirstHits, PreparedScene, Renderer
from stereovar.rig import VIEWS, make_rig
from stereovar.seeding import SEED_POLICIES, render_seed
from stereovar.statistics.registry import METHODS, register_method
from stereovar.statistics.summary import cross_scene_columns

from .test_ground_truth import REPO

W, H, FOV, BASELINE, DISPARITY = 64, 20, 60.0, 0.05, 4
FOCAL = 0.5 * W / math.tan(math.radians(FOV) / 2)
DEPTH = FOCAL * BASELINE / DISPARITY  # a plane at this depth has disparity exactly 4 px
GLASS_X = 0.05  # world x below which the plane is glass


def amplitude(points):
    """Per-pixel noise amplitude of the stub, a function of the scene point only."""
    return 0.05 + 0.04 * np.sin(points[..., 0] * 9.0) ** 2 + 0.02 * points[..., 1] ** 2


@dataclass
class PlaneScene(PreparedScene):
    """A diffuse plane z = DEPTH (glass left of GLASS_X) in front of the rig."""

    def hits(self, view):
        rays = self.rig.pixel_rays(view)
        origin = self.rig.origin(view)
        points = origin + rays * ((DEPTH - origin[2]) / rays[..., 2:3])
        return points

    def render(self, view, *, spp, seed, settings):
        rng = np.random.default_rng(seed)
        amp = amplitude(self.hits(view)) / math.sqrt(spp)
        return (0.5 + amp[..., None] * rng.standard_normal((H, W, 3))).astype(np.float32)

    def trace(self, view):
        points = self.hits(view)
        normals = np.broadcast_to([0.0, 0.0, -1.0], points.shape).copy()
        shape_index = np.where(points[..., 0] < GLASS_X, 1, 0).astype(np.int32)
        return FirstHits(np.ones((H, W), bool), points, normals, shape_index)

    def shape_materials(self):
        return np.array([1, 4], np.uint8), ["plane", "glass_pane"]  # diffuse, glass


class PlaneRenderer(Renderer):
    name = "stub_plane"

    def prepare(self, spec, *, rig, variant="auto", threads=None):
        provenance = {
            "scene": spec["name"],
            "scene_digest": "0" * 64,
            "renderer": self.name,
            "renderer_version": "1",
            "variant": "numpy",
        }
        return PlaneScene(make_rig(np.eye(4), FOV, **rig), spec=spec, provenance=provenance)


class TrueVariance(VarianceEstimator):
    """Returns the stub's analytic variance fields instead of estimating them."""

    name = "stub_truth"
    description = "analytic variance of the stub plane"

    def estimate(self, left, right):
        store = RenderStore(left[0])
        spp = int(store.attrs["spp"])
        prepared = PlaneRenderer().prepare({"name": "x"}, rig=RIG)
        fields = {v: amplitude(prepared.hits(v)) ** 2 / spp for v in VIEWS}
        variance = np.stack([fields[v] for v in VIEWS])
        return xr.Dataset(
            {
                "mean": (("view", "y", "x", "channel"), np.full((2, H, W, 3), 0.5, np.float32)),
                "variance": (("view", "y", "x"), variance),
                "finite": (("view", "y", "x"), np.ones((2, H, W), bool)),
                "n_nonfinite": (("view", "y", "x"), np.zeros((2, H, W), np.int32)),
            },
            coords={"view": list(VIEWS), "channel": ["R", "G", "B"]},
            attrs={"n_seeds": 0, "estimator": self.description},
        )


@pytest.fixture
def stubs():
    RENDERERS.register(PlaneRenderer.name, PlaneRenderer)
    ESTIMATORS.register(TrueVariance.name, TrueVariance)
    yield
    RENDERERS.unregister(PlaneRenderer.name)
    ESTIMATORS.unregister(TrueVariance.name)


RIG = {"width": W, "height": H, "baseline_m": BASELINE, "convention": "paper"}
SPEC = REPO / "scenes" / "scene_000.yaml"


@pytest.fixture
def plane_run(stubs, tmp_path):
    """Ground truth and two batches of 3 seeds of both views from the stub renderer."""
    from stereovar.jobs.ground_truth import ground_truth_job
    from stereovar.jobs.render import render_job

    gt = tmp_path / "gt.zarr"
    ground_truth_job(SPEC, gt, renderer=PlaneRenderer.name, **RIG)
    stores = {v: [] for v in VIEWS}
    for batch in ([0, 1, 2], [3, 4, 5]):
        outs = {v: tmp_path / f"{v}_seeds{batch[0]}.zarr" for v in VIEWS}
        render_job(SPEC, outs, seeds=batch, spp=4, renderer=PlaneRenderer.name, **RIG)
        for v in VIEWS:
            stores[v].append(outs[v])
    return gt, stores


def brute_variance(paths):
    """Eq. 1 by numpy on the stacked renders of one view (population variance, RGB mean)."""
    stack = np.concatenate([open_dataset(p)["radiance"].values for p in paths]).astype(float)
    return stack.var(axis=0).mean(axis=-1)


def test_stub_renderer_gives_the_analytic_ground_truth(plane_run):
    gt_path, _ = plane_run
    gt = open_dataset(gt_path).sel(view="left")
    inside = np.arange(W) + DISPARITY <= W - 1
    np.testing.assert_array_equal(gt["valid"].values, np.broadcast_to(inside, (H, W)))
    np.testing.assert_allclose(gt["disparity"].values[gt["valid"].values], DISPARITY, atol=1e-4)
    np.testing.assert_allclose(gt["depth"].values[gt["valid"].values], DEPTH, rtol=1e-6)
    assert gt.attrs["renderer"] == PlaneRenderer.name
    assert gt["glass"].values.any() and not gt["glass"].values.all()


def test_stub_renderer_flows_through_the_seeds_estimator_and_eq3(plane_run, tmp_path):
    from stereovar.jobs.correlation import correlation_job, warp_job
    from stereovar.jobs.variance import variance_job

    gt_path, stores = plane_run
    variance_job(stores["left"], stores["right"], tmp_path / "var.zarr")
    warp_job(tmp_path / "var.zarr", gt_path, tmp_path / "warp.zarr")
    rows = correlation_job(
        tmp_path / "var.zarr", tmp_path / "warp.zarr", gt_path, tmp_path / "c.csv"
    )

    var = open_dataset(tmp_path / "var.zarr")
    assert var.attrs["renderer"] == PlaneRenderer.name and var.attrs["n_seeds"] == 6
    sigma = {v: brute_variance(stores[v]) for v in VIEWS}
    np.testing.assert_allclose(var["variance"].sel(view="left").values, sigma["left"], rtol=1e-12)
    # Eq. 2 with an integer disparity is a shift: sigma_R(x + 4) at left pixel x.
    omega = np.zeros((H, W), bool)
    omega[:, : W - DISPARITY] = True
    warped = np.zeros((H, W))
    warped[:, : W - DISPARITY] = sigma["right"][:, DISPARITY:]
    glass = open_dataset(gt_path)["glass"].sel(view="left").values
    by_key = {(r["region"], r["method"]): r for r in rows}
    for region, mask in (("all", omega), ("non_glass", omega & ~glass), ("glass", omega & glass)):
        want = pearsonr(sigma["left"][mask], warped[mask])[0]
        assert by_key[(region, "warp")]["rho"] == pytest.approx(want, rel=1e-6)
        assert by_key[(region, "warp")]["n_pixels"] == mask.sum()
        unaligned = pearsonr(sigma["left"][mask], sigma["right"][mask])[0]
        assert by_key[(region, "no_warp")]["rho"] == pytest.approx(unaligned, rel=1e-6)
    assert {r["renderer"] for r in rows} == {PlaneRenderer.name}
    assert {r["estimator"] for r in rows} == {"seeds"}


def test_stub_estimator_replaces_eq1(plane_run, tmp_path):
    from stereovar.jobs.correlation import correlation_job, warp_job
    from stereovar.jobs.variance import variance_job

    gt_path, stores = plane_run
    variance_job(stores["left"], stores["right"], tmp_path / "v.zarr", estimator=TrueVariance.name)
    var = open_dataset(tmp_path / "v.zarr")
    assert var.attrs["estimator"] == TrueVariance.name
    assert var.attrs["estimator_description"] == TrueVariance.description
    assert var["variance"].attrs["units"] == "W2 m-4 sr-2"
    warp_job(tmp_path / "v.zarr", gt_path, tmp_path / "w.zarr")
    rows = correlation_job(tmp_path / "v.zarr", tmp_path / "w.zarr", gt_path, tmp_path / "c.csv")
    # The analytic fields depend on the scene point only, so once aligned they are equal.
    warp_all = next(r for r in rows if (r["region"], r["method"]) == ("all", "warp"))
    assert warp_all["rho"] == pytest.approx(1.0, abs=1e-9)
    assert {r["estimator"] for r in rows} == {TrueVariance.name}


def test_a_registered_statistic_reaches_the_rows_and_table_1(plane_run, tmp_path):
    from stereovar.jobs.correlation import correlation_job, warp_job
    from stereovar.jobs.tables import cross_scene_job
    from stereovar.jobs.variance import variance_job

    @register_method(
        "stub_spearman",
        "Spearman of sigma_L^2 and the warped sigma_R^2",
        transform=lambda values, settings: (rankdata(values[0]), rankdata(values[1])),
    )
    def stub_spearman(fields):
        return fields.left, fields.warped

    try:
        gt_path, stores = plane_run
        variance_job(stores["left"], stores["right"], tmp_path / "v.zarr")
        warp_job(tmp_path / "v.zarr", gt_path, tmp_path / "w.zarr")
        rows = correlation_job(
            tmp_path / "v.zarr", tmp_path / "w.zarr", gt_path, tmp_path / "c.csv"
        )
        names = [r["method"] for r in rows[: len(METHODS)]]
        assert names == list(METHODS.names()) and names[-1] == "stub_spearman"
        assert "mean_rho_stub_spearman" in cross_scene_columns()
        table = cross_scene_job([tmp_path / "c.csv"], {"csv": tmp_path / "t1.csv"}, spp=4)
        sigma_l = open_dataset(tmp_path / "v.zarr")["variance"].sel(view="left").values
        warped = open_dataset(tmp_path / "w.zarr")
        mask = warped["region_all"].values
        want = spearmanr(sigma_l[mask], warped["warped_variance"].values[mask])[0]
        assert table[0]["mean_rho_stub_spearman"] == pytest.approx(want, rel=1e-12)
    finally:
        METHODS.unregister("stub_spearman")
    assert "mean_rho_stub_spearman" not in cross_scene_columns()


def test_a_registered_seed_policy_is_one_function():
    SEED_POLICIES.register("stub_shared", lambda scene, view, spp, index: (scene, spp, index))
    try:
        left = render_seed("s", "left", 8, 2, policy="stub_shared")
        assert left == render_seed("s", "right", 8, 2, policy="stub_shared")
        assert left != render_seed("s", "left", 8, 3, policy="stub_shared")
    finally:
        SEED_POLICIES.unregister("stub_shared")
    assert render_seed("s", "left", 8, 2) != render_seed("s", "right", 8, 2)


def test_unknown_names_are_one_line_config_errors():
    with pytest.raises(ConfigError, match=r"render.renderer.*'povray'.*one of: cycles, mitsuba"):
        get_renderer("povray")
    with pytest.raises(ConfigError, match=r"render.estimator.*'jackknife'.*use one of: seeds"):
        get_estimator("jackknife")
