"""The analysis jobs end to end on synthetic render stores with known answers."""

import subprocess
import sys

import numpy as np
import pytest
import xarray as xr
from scipy.stats import pearsonr

from stereovar.errors import StoreError
from stereovar.io.store import open_dataset, write_dataset
from stereovar.io.tables import read_rows, write_tables
from stereovar.jobs.correlation import correlation_job, warp_job
from stereovar.jobs.tables import cross_scene_job, spp_sweep_job
from stereovar.jobs.variance import variance_job
from stereovar.statistics.registry import METHODS

H, W, D, N = 24, 48, 3, 6


def ground_truth(path, *, glass=True):
    glass_mask = np.zeros((2, H, W), bool)
    if glass:
        glass_mask[:, 4:12, 10:22] = True
    ds = xr.Dataset(
        {
            "disparity": (("view", "y", "x"), np.full((2, H, W), float(D), np.float32)),
            "valid": (("view", "y", "x"), np.ones((2, H, W), bool)),
            "glass": (("view", "y", "x"), glass_mask),
            "material": (("view", "y", "x"), np.where(glass_mask, 4, 1).astype(np.uint8)),
        },
        coords={"view": ["left", "right"]},
        attrs={"disparity_sign": 1, "convention": "paper"},
    )
    write_dataset(ds, path)


def renders(tmp_path, spp, *, nan_at=None, scene="synth"):
    """N seeds per view; the right view's noise amplitude is the left's shifted by +D px."""
    rng = np.random.default_rng(spp)
    yy, xx = np.mgrid[0:H, 0:W]
    amp = (1.0 + np.sin(xx / 3.0) ** 2 + yy / H) / np.sqrt(spp)  # varies along x and y
    # Right pixel x_R sees the scene point of left pixel x_R - D (x_R = x_L + D).
    amp_right = np.concatenate([amp[:, :D], amp[:, : W - D]], axis=1)
    paths = {"left": [], "right": []}
    for view, a in (("left", amp), ("right", amp_right)):
        for n in range(N):
            img = 2.0 + a[..., None] * rng.standard_normal((H, W, 3))
            if nan_at and view == "left" and n == 1:
                img[nan_at] = np.nan
            p = tmp_path / f"{scene}_{view}_spp{spp}_seed{n}.zarr"
            da = xr.DataArray(
                img.astype(np.float32),
                dims=("y", "x", "channel"),
                coords={"channel": ["R", "G", "B"]},
                name="radiance",
                attrs={"scene": scene, "spp": spp, "view": view, "seed_index": n},
            )
            write_dataset(da, p)
            paths[view].append(p)
    return paths


def brute_variance(paths):
    stack = np.stack([open_dataset(p)["radiance"].values.astype(np.float64) for p in paths])
    var = np.zeros((H, W))
    for j in range(H):
        for i in range(W):
            var[j, i] = np.mean(
                [((stack[:, j, i, c] - stack[:, j, i, c].mean()) ** 2).mean() for c in range(3)]
            )
    return var, np.isfinite(stack).all(axis=(0, 3))


@pytest.fixture
def chain(tmp_path):
    ground_truth(tmp_path / "gt.zarr")
    paths = renders(tmp_path, 16, nan_at=(5, 7))
    variance_job(paths["left"], paths["right"], tmp_path / "var.zarr")
    warp_job(tmp_path / "var.zarr", tmp_path / "gt.zarr", tmp_path / "warp.zarr")
    rows = correlation_job(
        tmp_path / "var.zarr", tmp_path / "warp.zarr", tmp_path / "gt.zarr", tmp_path / "corr.csv"
    )
    return tmp_path, paths, rows


def test_chain_matches_brute_force_eq1_eq2_eq3(chain):
    tmp_path, paths, rows = chain
    var_l, fin_l = brute_variance(paths["left"])
    var_r, _ = brute_variance(paths["right"])
    v = open_dataset(tmp_path / "var.zarr")
    np.testing.assert_allclose(
        v["variance"].sel(view="left").values[fin_l], var_l[fin_l], rtol=1e-5
    )
    assert not v["finite"].sel(view="left").values[5, 7]
    # Eq. 2 with an integer disparity is an exact shift; Omega drops the last D columns
    # and the non-finite pixel.
    omega = np.ones((H, W), bool)
    omega[:, W - D :] = False
    omega &= fin_l
    w = open_dataset(tmp_path / "warp.zarr")
    np.testing.assert_array_equal(w["omega"].values, omega)
    warped = np.zeros((H, W))
    warped[:, : W - D] = var_r[:, D:]
    glass = np.zeros((H, W), bool)
    glass[4:12, 10:22] = True
    csv = {(r["region"], r["method"]): r for r in read_rows(tmp_path / "corr.csv")}
    for region, mask in (("all", omega), ("non_glass", omega & ~glass), ("glass", omega & glass)):
        row = csv[(region, "warp")]
        assert row["n_pixels"] == mask.sum()
        assert row["rho"] == pytest.approx(pearsonr(var_l[mask], warped[mask])[0], abs=1e-6)
        no_warp = csv[(region, "no_warp")]
        assert no_warp["rho"] == pytest.approx(pearsonr(var_l[mask], var_r[mask])[0], abs=1e-6)
        assert row["scene"] == "synth" and row["spp"] == 16 and row["n_seeds"] == N
    # The shifted amplitude pattern makes the aligned fields agree far better.
    assert csv[("all", "warp")]["rho"] > csv[("all", "no_warp")]["rho"] + 0.2
    assert csv[("all", "warp")]["n_nonfinite"] == 1
    assert len(rows) == 3 * len(METHODS)


def test_scene_without_glass_gives_nan_glass_rows_with_reason(tmp_path):
    ground_truth(tmp_path / "gt.zarr", glass=False)
    paths = renders(tmp_path, 4)
    variance_job(paths["left"], paths["right"], tmp_path / "var.zarr")
    warp_job(tmp_path / "var.zarr", tmp_path / "gt.zarr", tmp_path / "warp.zarr")
    rows = correlation_job(
        tmp_path / "var.zarr", tmp_path / "warp.zarr", tmp_path / "gt.zarr", tmp_path / "corr.csv"
    )
    glass = [r for r in read_rows(tmp_path / "corr.csv") if r["region"] == "glass"]
    assert len(glass) == len(METHODS)
    assert all(np.isnan(r["rho"]) and "no glass" in r["reason"] for r in glass)
    assert all(np.isfinite(r["rho"]) for r in rows if r["region"] != "glass")


def test_damaged_store_is_a_one_line_error_naming_it(tmp_path):
    paths = renders(tmp_path, 4)
    broken = paths["right"][2]
    chunk = next(p for p in (broken / "radiance").iterdir() if not p.name.startswith("."))
    chunk.unlink()
    with pytest.raises(StoreError) as err:
        variance_job(paths["left"], paths["right"], tmp_path / "var.zarr")
    assert str(broken) in str(err.value) and f" {broken} -- --force`" in str(err.value)
    assert "\n" not in str(err.value)
    assert not (tmp_path / "var.zarr").exists()
    code = (
        "from stereovar.jobs.common import run_job\n"
        "from stereovar.jobs.variance import variance_job\n"
        f"run_job(None, variance_job, left={[str(p) for p in paths['left']]!r}, "
        f"right={[str(p) for p in paths['right']]!r}, out={str(tmp_path / 'v.zarr')!r})\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert sum("error:" in line for line in proc.stderr.splitlines()) == 1


def test_tables_from_several_scenes_and_spps(tmp_path):
    ground_truth(tmp_path / "gt.zarr")
    corr, var, warp = [], [], []
    for spp in (4, 16, 64):
        paths = renders(tmp_path, spp)
        for name, lst in (("var", var), ("warp", warp), ("corr", corr)):
            lst.append(tmp_path / f"{name}{spp}.{'csv' if name == 'corr' else 'zarr'}")
        variance_job(paths["left"], paths["right"], var[-1])
        warp_job(var[-1], tmp_path / "gt.zarr", warp[-1])
        correlation_job(var[-1], warp[-1], tmp_path / "gt.zarr", corr[-1])
    outputs = {k: tmp_path / f"sweep.{k}" for k in ("csv", "md", "tex")}
    fit_outputs = {k: tmp_path / f"fit.{k}" for k in ("csv", "md", "tex")}
    fit = spp_sweep_job(corr, var, warp, outputs, fit_outputs)
    # The noise amplitude scales as 1/sqrt(spp): mean variance as spp^-1.
    for region in ("all", "non_glass", "glass"):
        assert fit[region]["slope"] == pytest.approx(-1.0, abs=0.1)
    sweep = read_rows(outputs["csv"])
    assert [r["spp"] for r in sweep] == [4, 16, 64]
    # Table 1 over "scenes" (here the three SPPs relabelled as scenes at one SPP).
    rows = []
    for k, path in enumerate(corr):
        for r in read_rows(path):
            rows.append({**r, "scene": f"s{k}", "spp": 16})
    relabelled = tmp_path / "all.csv"
    from stereovar.io.tables import write_tables
    from stereovar.statistics.rows import CORRELATION_COLUMNS

    write_tables(rows, CORRELATION_COLUMNS, {"csv": relabelled})
    table = cross_scene_job([relabelled], {"csv": tmp_path / "t1.csv"}, spp=16)
    all_row = next(r for r in table if r["region"] == "all")
    rhos = [r["rho"] for r in rows if r["region"] == "all" and r["method"] == "warp"]
    assert all_row["mean_rho"] == pytest.approx(np.mean(rhos))
    assert all_row["std_rho"] == pytest.approx(np.std(rhos, ddof=1))
    assert all_row["n_scenes"] == 3


def test_intervention_job_and_table(tmp_path, caplog):
    from stereovar.jobs.figures import margin_figure_job
    from stereovar.jobs.intervention import intervention_job, intervention_table_job

    ground_truth(tmp_path / "gt.zarr")
    paths = renders(tmp_path, 16)
    rows = intervention_job(
        paths["left"],
        paths["right"],
        tmp_path / "gt.zarr",
        tmp_path / "iv.csv",
        tmp_path / "margins.csv",
        window=3,
        block=8,
        margin_samples=40,
    )
    # D defaults to the largest ground-truth disparity plus the margin.
    assert {r["max_disparity"] for r in rows} == {D + 4}
    stored = read_rows(tmp_path / "iv.csv")
    # 5 metrics x 3 regions (all, non_glass, glass) x 2 conditions
    assert len(stored) == 30 and stored[0]["scene"] == "synth"
    assert {r["region"] for r in stored} == {"all", "non_glass", "glass"}
    samples = read_rows(tmp_path / "margins.csv")
    groups = {(s["cost"], s["region"], s["condition"]) for s in samples}
    assert {s["scene"] for s in samples} == {"synth"} and len(groups) >= 4
    for key in groups:  # at most margin_samples each, every one finite
        picked = [s for s in samples if (s["cost"], s["region"], s["condition"]) == key]
        assert 0 < len(picked) <= 40 and all(np.isfinite(s["margin"]) for s in picked)
    margin_figure_job([tmp_path / "margins.csv"], tmp_path / "fig4.png")
    assert (tmp_path / "fig4.png").read_bytes()[:4] == b"\x89PNG"
    with caplog.at_level("WARNING", logger="stereovar"):
        intervention_job(
            paths["left"],
            paths["right"],
            tmp_path / "gt.zarr",
            tmp_path / "iv2.csv",
            tmp_path / "margins2.csv",
            window=3,
            block=8,
            max_disparity=2,
        )
    warning = " ".join(r.getMessage() for r in caplog.records if r.levelname == "WARNING")
    assert "unscoreable" in warning and str(H * W) in warning
    second = [
        dict(r, scene="other", value=r["value"] * 2 if np.isfinite(r["value"]) else r["value"])
        for r in stored
    ]
    write_tables(stored + second, list(stored[0]), {"csv": tmp_path / "both.csv"})
    table = intervention_table_job([tmp_path / "both.csv"], {"csv": tmp_path / "t3.csv"})
    row = next(
        r
        for r in table
        if (r["cost"], r["metric"], r["region"]) == ("residual_sad", "wta_accuracy", "non_glass")
    )
    v_n = [
        r["value"]
        for r in stored + second
        if r["cost"] == "residual_sad"
        and r["metric"] == "wta_accuracy"
        and r["region"] == "non_glass"
        and r["condition"] == "normal"
    ]
    v_d = [
        r["value"]
        for r in stored + second
        if r["cost"] == "residual_sad"
        and r["metric"] == "wta_accuracy"
        and r["region"] == "non_glass"
        and r["condition"] == "decorrelated"
    ]
    assert row["normal_mean"] == pytest.approx(np.mean(v_n))
    assert row["normal_std"] == pytest.approx(np.std(v_n, ddof=1))
    assert row["relative_change"] == pytest.approx(
        (np.mean(v_n) - np.mean(v_d)) / abs(np.mean(v_d))
    )


def test_renders_of_several_back_ends_stop_the_variance_job(tmp_path):
    import json

    from stereovar.errors import BackendError

    paths = renders(tmp_path, 4)
    for view, stores in paths.items():
        for k, store in enumerate(stores):
            variant = "scalar_rgb" if (view, k) == ("right", 2) else "llvm_ad_rgb"
            attrs = {"renderer": "mitsuba", "renderer_version": "3.9.1", "variant": variant}
            (store / ".zattrs").write_text(json.dumps(attrs))
    with pytest.raises(BackendError) as err:
        variance_job(paths["left"], paths["right"], tmp_path / "var.zarr")
    message = str(err.value)
    assert "\n" not in message and "would mix back ends" in message
    assert (
        "scalar_rgb" in message and "llvm_ad_rgb" in message and str(paths["right"][2]) in message
    )
    assert not (tmp_path / "var.zarr").exists()
    variance_job(paths["left"], paths["right"], tmp_path / "var.zarr", allow_mixed_backends=True)
    assert (tmp_path / "var.zarr").is_dir()
