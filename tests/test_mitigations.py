"""The transform seam and the mitigations: a stub transform with an analytic effect reaches the
variance fields, Eq. 3, the per-scene mitigation rows and the mitigation table; the shared
seed policy couples the views; the table summarises exactly what its inputs say."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import pearsonr

from stereovar.errors import ConfigError
from stereovar.io.store import open_dataset
from stereovar.layout import (
    NONE,
    ground_truth_store,
    mitigation_rows,
    render_store,
    run_prefix,
    source_key,
    source_key_pattern,
    split_source_key,
)
from stereovar.mitigations import mitigation_runs, resolve_mitigation
from stereovar.renderers.base import SampleMoments
from stereovar.rig import VIEWS
from stereovar.transforms import TRANSFORMS, Transform

from .test_architecture import RIG, SPEC, W, plane_run, stubs  # noqa: F401 (fixtures)

GAIN, OFFSET = 3.0, 0.25


def gain_offset(inputs, **_):
    """The stub transform: an affine map of the pixels, whose every effect is analytic."""
    return (GAIN * inputs.render.astype(np.float64) + OFFSET).astype(np.float32)


@pytest.fixture
def stub_transform():
    TRANSFORMS.register("stub_gain", Transform("stub_gain", "affine stub", gain_offset))
    yield "stub_gain"
    TRANSFORMS.unregister("stub_gain")


def stack(paths):
    return np.concatenate([open_dataset(p)["radiance"].values for p in paths]).astype(np.float64)


def write_reference(path, mean, view):
    """A moment store whose two halves both hold ``mean`` exactly (zero sample variance)."""
    from stereovar.io.moments import moments_dataset
    from stereovar.io.store import write_dataset

    count = np.full(mean.shape[:2], 8, np.int32)
    half = SampleMoments(mean.astype(np.float32), (mean**2).astype(np.float32), count)
    ds = moments_dataset([half, half], view=view, sampler_seeds=[1, 2], half_spp=[8, 8], attrs={})
    write_dataset(ds, path)
    return path


def test_layout_keys_sources_transforms_and_estimators():
    assert source_key("mitsuba", NONE) == "mitsuba"
    assert render_store("mitsuba", "s", "left", 32, "0-7") == (
        "results/mitsuba/renders/s/left/spp32/seeds0-7.zarr"
    )
    assert render_store("mitsuba", "s", "left", 32, "0-7", "denoise") == (
        "results/mitsuba/denoise/renders/s/left/spp32/seeds0-7.zarr"
    )
    assert run_prefix("audit/team", "seeds", "equalise") == "results/audit/team/equalise/seeds"
    assert ground_truth_store("mitsuba/denoise", "s") == "results/ground_truth/s.zarr"
    assert (
        ground_truth_store("audit/team/denoise", "f0") == "results/audit/team/ground_truth/f0.zarr"
    )
    assert mitigation_rows("mitsuba", "seeds", "s", 32, "sensor_only") == (
        "results/mitsuba/sensor_only/seeds/mitigation/s/spp32.csv"
    )
    for key in ("mitsuba", "mitsuba/denoise", "audit/team", "audit/team/equalise"):
        assert source_key(*split_source_key(key)) == key
    import re

    pattern = re.compile(source_key_pattern(["mitsuba"], ["denoise"]))
    assert pattern.fullmatch("mitsuba/denoise") and pattern.fullmatch("audit/x/denoise")
    assert not pattern.fullmatch("mitsuba/seeds") and not pattern.fullmatch("cycles")


def test_mitigation_runs_follow_the_config():
    config = {
        "scenes": ["a", "b"],
        "render": {"renderer": "mitsuba", "spp": 32, "spp_sweep": {"scene": "a", "spp": [32, 128]}},
        "mitigations": {"names": ["spp_x4", "spp_x2", "shared_seed", "equalise"]},
    }
    runs = {r.name: r for r in mitigation_runs(config)}
    assert list(runs) == ["none", "spp_x4", "spp_x2", "shared_seed", "equalise"]
    assert (runs["spp_x4"].spp, runs["spp_x4"].scenes) == (128, ("a", "b"))  # every scene
    assert (runs["spp_x2"].spp, runs["spp_x2"].scenes) == (64, ("a", "b"))
    assert runs["shared_seed"].mitigation.seed_policy == "shared"
    assert runs["equalise"].transform == "equalise" and runs["none"].transform == NONE
    with pytest.raises(ConfigError, match="unknown mitigation 'blur'.*spp_xK.*denoise"):
        resolve_mitigation("blur")
    with pytest.raises(ConfigError):
        resolve_mitigation("spp_x1")


def test_a_stub_transform_reaches_eq1_eq3_and_the_mitigation_table(
    plane_run,  # noqa: F811 (the fixture imported from test_architecture)
    stub_transform,
    tmp_path,
):
    from stereovar.jobs.correlation import correlation_job, warp_job
    from stereovar.jobs.mitigation_scene import mitigation_scene_job
    from stereovar.jobs.mitigations import mitigations_table_job
    from stereovar.jobs.transform import transform_job
    from stereovar.jobs.variance import variance_job

    gt, stores = plane_run
    out = {v: [] for v in VIEWS}
    for view in VIEWS:
        for k, batch in enumerate(([0, 1, 2], [3, 4, 5])):
            path = tmp_path / f"t_{view}_{k}.zarr"
            transform_job(stores[view], path, transform=stub_transform, batch=batch, view=view)
            out[view].append(path)
    ds = open_dataset(out["left"][1])
    assert ds.attrs["transform"] == stub_transform and list(ds["seed"].values) == [3, 4, 5]
    assert len(set(ds["transform_seed"].values.tolist())) == 3
    np.testing.assert_allclose(
        stack(out["left"]), GAIN * stack(stores["left"]) + OFFSET, rtol=1e-6, atol=1e-6
    )

    rows = {}
    for name, views in (("none", stores), ("stub", out)):
        run = tmp_path / name
        run.mkdir()
        variance_job(views["left"], views["right"], run / "v.zarr")
        warp_job(run / "v.zarr", gt, run / "w.zarr")
        correlation_job(run / "v.zarr", run / "w.zarr", gt, run / "c.csv")
        rows[name] = run
    v0, v1 = (open_dataset(rows[n] / "v.zarr")["variance"].values for n in ("none", "stub"))
    np.testing.assert_allclose(v1, GAIN**2 * v0, rtol=1e-5)  # Var[gX + c] = g^2 Var[X]

    # The reference: the stub plane's clean value 0.5 in every pixel, exactly.
    reference = {
        v: write_reference(tmp_path / f"ref_{v}.zarr", np.full((20, W, 3), 0.5), v) for v in VIEWS
    }
    scene_rows = {}
    for name, views in (("none", stores), ("stub", out)):
        path = tmp_path / f"{name}_mitigation.csv"
        scene_rows[name] = mitigation_scene_job(views["left"], views["right"], gt, reference, path)
    by = {n: {(r["region"], r["quantity"]): r for r in rs} for n, rs in scene_rows.items()}
    for region in ("all", "non_glass", "glass"):
        for q in ("residual_rho_gt", "residual_rho_zero"):  # Pearson ignores gain and offset
            assert by["stub"][(region, q)]["value"] == pytest.approx(
                by["none"][(region, q)]["value"], abs=1e-6
            )
    both = np.concatenate([stack(out[v]) for v in VIEWS])
    assert by["stub"][("all", "bias")]["value"] == pytest.approx(np.mean(both - 0.5), rel=1e-9)
    mse = np.mean((both - 0.5) ** 2)
    assert by["stub"][("all", "mse")]["value"] == pytest.approx(mse, rel=1e-9)
    assert by["stub"][("all", "psnr")]["value"] == pytest.approx(-10 * np.log10(mse), rel=1e-9)
    assert math.isfinite(by["stub"][("all", "transform_ms_per_mpix")]["value"])
    assert math.isnan(by["none"][("all", "transform_ms_per_mpix")]["value"])

    runs = [
        {
            "mitigation": name,
            "kind": "transform",
            "description": name,
            "spp": 4,
            "correlation": [rows[name] / "c.csv"],
            "intervention": [],
            "scene_rows": [tmp_path / f"{name}_mitigation.csv"],
        }
        for name in ("none", "stub")
    ]
    outputs = {ext: tmp_path / f"mitigations.{ext}" for ext in ("csv", "md", "tex", "html")}
    table = mitigations_table_job(runs, outputs, figure=tmp_path / "fig.png")
    got = {(r["mitigation"], r["region"]): r for r in table}
    # Pearson ignores gain and offset; the intensity control (a polynomial in ln mu) does not
    # ignore the offset, so it is not compared.
    for region in ("all", "non_glass", "glass"):
        for col in ("rho", "null_shift", "residual_rho_gt", "residual_rho_zero"):
            assert got[("stub", region)][col] == pytest.approx(got[("none", region)][col], abs=1e-6)
    assert (tmp_path / "fig.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_missing_reads_are_refused_in_one_line(plane_run, tmp_path):  # noqa: F811
    from stereovar.jobs.transform import transform_job

    TRANSFORMS.register(
        "stub_needs_albedo",
        Transform("stub_needs_albedo", "needs albedo", gain_offset, reads=("albedo",)),
    )
    try:
        _, stores = plane_run
        with pytest.raises(ConfigError) as err:
            transform_job(
                stores["left"],
                tmp_path / "x.zarr",
                transform="stub_needs_albedo",
                batch=[0],
                view="left",
            )
        assert "albedo" in str(err.value) and "\n" not in str(err.value)
        assert not (tmp_path / "x.zarr").exists()
    finally:
        TRANSFORMS.unregister("stub_needs_albedo")


@pytest.mark.parametrize(("policy", "coupled"), [("shared", True), ("independent", False)])
def test_shared_seed_couples_the_views_at_zero_disparity(tmp_path, policy, coupled):
    """Mitsuba with one seed for both views and (almost) no baseline renders the same image
    twice: the residual correlation at zero disparity is 1 to float precision. Independent
    seeds give about 0, inside its interval."""
    from stereovar.jobs.render import render_job
    from stereovar.statistics.bootstrap import BootstrapSettings
    from stereovar.statistics.residuals import residual_correlation

    rig = {"width": 32, "height": 18, "baseline_m": 1e-9, "convention": "paper"}
    outs = {v: tmp_path / f"{v}.zarr" for v in VIEWS}
    render_job(SPEC, outs, seeds=[0, 1, 2, 3], spp=2, seed_policy=policy, **rig)
    left, right = (stack([outs[v]]) for v in VIEWS)
    seeds = {v: open_dataset(outs[v])["sampler_seed"].values.tolist() for v in VIEWS}
    assert (seeds["left"] == seeds["right"]) == coupled
    mask = {"all": np.ones((18, 32), bool)}
    (row,) = residual_correlation(
        left,
        right,
        np.zeros((18, 32)),
        sign=1,
        masks=mask,
        alignments=("zero",),
        settings=BootstrapSettings(tile=4, reps=200),
    )
    if coupled:
        assert row["rho"] == pytest.approx(1.0, abs=1e-5)
    else:
        # each pixel's residuals standardised over its seeds (pixels whose seeds all agree
        # have no correlation and are left out), then pooled
        lum_l, lum_r = left.mean(-1), right.mean(-1)
        ok = (np.ptp(lum_l, axis=0) > 0) & (np.ptp(lum_r, axis=0) > 0)
        ok &= np.isfinite(lum_l).all(0) & np.isfinite(lum_r).all(0)
        z_l, z_r = (
            ((lum - lum.mean(0)) / lum.std(0, ddof=1))[:, ok].ravel() for lum in (lum_l, lum_r)
        )
        assert row["n_pixels"] == ok.sum()
        assert row["rho"] == pytest.approx(pearsonr(z_l, z_r)[0], abs=1e-9)
        # about 0: 2304 seed-pixel pairs give a standard error near 0.02 (more with the
        # pixels' spatial dependence); one fixed dataset's interval need not cover 0 on every
        # CPU, whose renders differ in the last bits
        assert abs(row["rho"]) < 0.1


def test_the_table_summarises_its_inputs_exactly():
    from stereovar.statistics.mitigations import mitigation_table
    from stereovar.statistics.t_intervals import t_interval

    from .test_across import on_fisher_z

    rng = np.random.default_rng(3)
    corr, scene_rows, intervention = [], [], []
    for k, scene in enumerate(["a", "b", "c"]):
        for method in ("warp", "partial", "null_shift", "sensor_sim"):
            rho = float(rng.uniform(-0.2, 0.8))
            corr.append(
                {
                    "scene": scene,
                    "region": "all",
                    "method": method,
                    "rho": rho,
                    "boot_low": rho - 0.1 - 0.01 * k,
                    "boot_high": rho + 0.12,
                    "chance_se": 0.2 * k * (method == "partial"),
                    "n_seeds": 8,
                }
            )
        for q in ("residual_rho_gt", "residual_rho_zero"):
            v = float(rng.normal(0, 0.05))
            scene_rows.append(
                {
                    "scene": scene,
                    "region": "all",
                    "quantity": q,
                    "value": v,
                    "low": v - 0.02,
                    "high": v + 0.03,
                }
            )
        for q, v in (
            ("psnr", 20.0 + k),
            ("relative_mse", 0.1 * k),
            ("bias", 0.01),
            ("relative_bias", 0.02),
            ("transform_ms_per_mpix", 100.0 + k),
        ):
            scene_rows.append(
                {
                    "scene": scene,
                    "region": "all",
                    "quantity": q,
                    "value": v,
                    "low": math.nan,
                    "high": math.nan,
                }
            )
        for condition, value in (("normal", 0.6 + 0.1 * k), ("decorrelated", 0.5)):
            for cost in ("residual_sad", "variance_cost"):
                intervention.append(
                    {
                        "scene": scene,
                        "cost": cost,
                        "metric": "wta_accuracy",
                        "region": "all",
                        "source": "render",
                        "condition": condition,
                        "value": value,
                        "chance": 0.2,
                        "n_pixels": 100,
                    }
                )
    nulls = [
        {"scene": scene, "transform": "denoise", "region": "all", "method": "partial",
         "null_rho": 0.1 * k, "null_se": 0.01, "chance_sd": 0.02, "n": 16, "margin": 0.05}
        for k, scene in enumerate(["a", "b", "c"])
    ]
    # the margin of "removed" is the untransformed frames' detectable effect
    nulls.append({**nulls[0], "transform": "none", "margin": 0.05})
    (row,) = mitigation_table(
        [
            {
                "mitigation": "m",
                "kind": "transform",
                "description": "d",
                "spp": 32,
                "calibration_transform": "denoise",
                "correlation": corr,
                "intervention": intervention,
                "scene_rows": scene_rows,
            }
        ],
        nulls,
    )
    part = [r for r in corr if r["method"] == "partial"]
    # a correlation: the scenes' bootstrap errors combined as independent normals, the
    # interval of that length placed on Fisher's z about the mean
    z = 1.959963984540054
    rho = sum(r["rho"] for r in part) / 3
    half = z * math.sqrt(sum(((r["boot_high"] - r["boot_low"]) / (2 * z)) ** 2 for r in part)) / 3
    want = (rho, *on_fisher_z(rho, half))
    assert (row["partial"], row["partial_low"], row["partial_high"]) == pytest.approx(want)
    # the Monte Carlo-specific part: each scene's partial minus its null; the larger of the
    # bootstrap's and the chance standard error, with the null's standard error in
    # quadrature; then the scenes combined (scene a's chance term 0 is below its bootstrap's
    # 0.056, scene c's 0.4 above)
    diffs = [r["rho"] - 0.1 * k for k, r in enumerate(part)]
    halves = [
        z * math.sqrt(max((r["boot_high"] - r["boot_low"]) / (2 * z), 0.2 * k) ** 2 + 0.01**2)
        for k, r in enumerate(part)
    ]
    mean = sum(diffs) / 3
    half = z * math.sqrt(sum((h / z) ** 2 for h in halves)) / 3
    assert (row["mc_specific"], row["mc_specific_low"], row["mc_specific_high"]) == (
        pytest.approx((mean, mean - half, mean + half))
    )
    assert row["null_partial"] == pytest.approx(0.1) and row["margin"] == 0.05
    assert row["mc_cue"] == (
        "remains" if mean - half > 0 else "reversed" if mean + half < 0 else "inconclusive"
    )
    assert (row["psnr"], row["psnr_low"], row["psnr_high"]) == pytest.approx(
        t_interval([20.0, 21.0, 22.0])
    )
    lift = t_interval([0.6 - 0.2, 0.7 - 0.2, 0.8 - 0.2])
    assert (row["cs_lift"], row["cs_lift_low"], row["cs_lift_high"]) == pytest.approx(lift)
    effect = t_interval([0.1, 0.2, 0.3])
    assert row["ce_shuffle_effect"] == pytest.approx(effect[0])
    assert row["transform_ms_per_mpix"] == pytest.approx(101.0)
    assert (row["n_scenes"], row["n_seeds"]) == (3, 8)


@pytest.mark.workflow
def test_the_mitigations_target_end_to_end(tmp_path):
    """A tiny run of `snakemake mitigations`: a dry run writes nothing; the table has every
    mitigation and region; shared seeds couple the views at zero disparity and the denoiser
    raises the PSNR against the converged reference."""
    import copy

    from stereovar.io.tables import read_rows

    from .test_workflow import TINY, copy_workflow, snakemake

    config = copy.deepcopy(TINY)
    config["scenes"] = ["scene_000"]
    config["mitigations"] = {"names": ["shared_seed", "denoise"], "reference_spp": 16, "aux_spp": 2}
    root = copy_workflow(tmp_path / "wf", config)
    before = sorted(p.relative_to(root) for p in root.rglob("*"))
    dry = snakemake(root, "-n", "mitigations")
    assert "render_policy" in dry.stdout and "render_aux" in dry.stdout
    assert "transform" in dry.stdout
    assert sorted(p.relative_to(root) for p in root.rglob("*") if ".snakemake" not in p.parts) == [
        p for p in before if ".snakemake" not in p.parts
    ]
    snakemake(root, "-j2", "mitigations")
    rows = {
        (r["mitigation"], r["region"]): r
        for r in read_rows(root / "results/tables/mitigations.csv")
    }
    assert {m for m, _ in rows} == {"none", "shared_seed", "denoise"}
    assert {g for _, g in rows} == {"all", "non_glass", "glass"}
    shared, none = rows[("shared_seed", "all")], rows[("none", "all")]
    assert shared["residual_rho_zero_low"] > max(0.0, none["residual_rho_zero_high"])
    assert rows[("denoise", "all")]["psnr"] > none["psnr"]
    store = open_dataset(root / "results/mitsuba/denoise/renders/scene_000/left/spp2/seeds0-1.zarr")
    assert store.attrs["transform"] == "denoise"
    assert store.attrs["transform_aux"] == "albedo,normal"
    policy = open_dataset(
        root / "results/mitsuba/shared_seed/renders/scene_000/right/spp2/seeds0-1.zarr"
    )
    left = open_dataset(
        root / "results/mitsuba/shared_seed/renders/scene_000/left/spp2/seeds0-1.zarr"
    )
    assert policy["sampler_seed"].values.tolist() == left["sampler_seed"].values.tolist()
    assert (root / "results/figures/mitigations.png").read_bytes()[:4] == b"\x89PNG"
    # nothing to do on a second run
    assert "Nothing to be done" in snakemake(root, "-n", "mitigations").stdout


@pytest.mark.workflow
def test_a_render_time_mitigation_is_refused_for_an_audit(tmp_path):
    """An audit's renders are given: `shared_seed` is refused in one line before any job
    (tests/test_audit_workflow.py runs `denoise` on a synthetic audit end to end)."""
    from stereovar.audit.synthetic import write_synthetic_audit

    from .test_workflow import TINY, copy_workflow, snakemake

    root = copy_workflow(tmp_path / "wf", TINY)
    settings, _ = write_synthetic_audit(root / "data", n_frames=1, width=64, height=48, n_seeds=3)
    settings["renders"] = "data/renders/{frame}/{view}/seed_{seed}.exr"
    settings["disparity"] = "data/disparity/{frame}.pfm"
    refused = snakemake(
        root, "-n", check=False, config={"audit": {**settings, "mitigations": ["shared_seed"]}}
    )
    assert refused.returncode != 0
    (line,) = [x for x in refused.stderr.splitlines() if "audit.mitigations" in x]
    assert "shared_seed" in line and "denoise" in line
    assert not (root / "results").exists()
