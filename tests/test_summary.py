"""Tables 1 and 2: cross-scene statistics and the SPP sweep fit against hand computations."""

import math

import numpy as np
import pytest

from stereovar.statistics.summary import (
    cross_scene_table,
    mean_variance_by_region,
    spp_sweep_table,
    sweep_entry,
)

NAN = float("nan")


def row(scene, region, method, rho, reason="", spp=512):
    return {
        "scene": scene,
        "spp": spp,
        "region": region,
        "method": method,
        "rho": rho,
        "reason": reason,
    }


def scene_rows():
    return [
        row("s0", "all", "warp", 0.70),
        row("s0", "all", "no_warp", 0.30),
        row("s1", "all", "warp", 0.80),
        row("s1", "all", "no_warp", 0.40),
        row("s2", "all", "warp", 0.75),
        row("s2", "all", "no_warp", NAN, "constant"),
        row("s0", "non_glass", "warp", 0.9),
        row("s0", "non_glass", "no_warp", 0.5),
        row("s1", "non_glass", "warp", NAN, "fewer than 30 valid pixels (n=3)"),
        row("s1", "non_glass", "no_warp", NAN, "fewer than 30 valid pixels (n=3)"),
        row("s2", "non_glass", "warp", 0.7),
        row("s2", "non_glass", "no_warp", 0.1),
        row("s0", "glass", "warp", NAN, "no glass pixels in the scene"),
        row("s0", "glass", "no_warp", NAN, "no glass pixels in the scene"),
        row("s1", "glass", "warp", NAN, "fewer than 30 valid pixels (n=3)"),
        row("s1", "glass", "no_warp", NAN, "fewer than 30 valid pixels (n=3)"),
    ]


def test_cross_scene_statistics_by_hand():
    table = {r["region"]: r for r in cross_scene_table(scene_rows())}
    assert [r["region"] for r in cross_scene_table(scene_rows())] == ["all", "non_glass", "glass"]
    a = table["all"]
    assert a["n_scenes"] == 3 and a["reason"] == "" and a["spp"] == 512
    assert a["mean_rho"] == pytest.approx(0.75)
    # sample std of 0.70, 0.80, 0.75: deviations -0.05, 0.05, 0 -> sqrt(0.005 / 2)
    assert a["std_rho"] == pytest.approx(0.05)
    assert (a["min_rho"], a["max_rho"]) == (pytest.approx(0.70), pytest.approx(0.80))
    assert a["mean_rho_no_warp"] == pytest.approx(0.35)
    n = table["non_glass"]
    assert n["n_scenes"] == 2 and n["mean_rho"] == pytest.approx(0.8)
    assert n["std_rho"] == pytest.approx(math.sqrt(0.02))
    assert n["mean_rho_no_warp"] == pytest.approx(0.3)
    g = table["glass"]
    assert g["n_scenes"] == 0
    assert all(math.isnan(g[k]) for k in ("mean_rho", "std_rho", "min_rho", "max_rho"))
    assert math.isnan(g["mean_rho_no_warp"])
    assert g["reason"].startswith("no scene has a finite rho in region glass")
    assert "no glass pixels in the scene" in g["reason"]


def test_single_scene_has_undefined_std():
    rows = [row("s0", "all", "warp", 0.7)]
    a = cross_scene_table(rows)[0]
    assert a["n_scenes"] == 1 and a["mean_rho"] == pytest.approx(0.7) and math.isnan(a["std_rho"])


def test_mixed_spp_and_duplicates_are_rejected():
    rows = scene_rows() + [row("s0", "all", "warp", 0.7, spp=128)]
    with pytest.raises(ValueError, match="spp"):
        cross_scene_table(rows)
    assert cross_scene_table(rows, spp=128)[0]["mean_rho"] == pytest.approx(0.7)
    with pytest.raises(ValueError, match="duplicate"):
        cross_scene_table(scene_rows() + [row("s0", "all", "warp", 0.1)])


def test_mean_variance_by_region():
    sigma = np.arange(12.0).reshape(3, 4)
    sigma[0, 1] = np.nan
    masks = {
        "all": np.ones((3, 4), bool),
        "glass": np.eye(3, 4, dtype=bool),
        "non_glass": np.zeros((3, 4), bool),
    }
    out = mean_variance_by_region(sigma, masks)
    assert out["all"] == pytest.approx((66.0 - 1.0) / 11)
    assert out["glass"] == pytest.approx((0 + 5 + 10) / 3)
    assert math.isnan(out["non_glass"])


def test_sweep_entry_takes_warp_rows():
    rows = [
        {"region": "all", "method": "warp", "rho": 0.7},
        {"region": "all", "method": "no_warp", "rho": 0.3},
        {"region": "glass", "method": "warp", "rho": 0.4},
    ]
    entry = sweep_entry(256, rows, {"all": 2.0, "glass": 5.0})
    assert entry == {
        "spp": 256,
        "mean_var_left_all": 2.0,
        "mean_var_left_glass": 5.0,
        "rho_all": 0.7,
        "rho_glass": 0.4,
    }


def sweep(values_all, values_glass, values_non_glass, spps=(2048, 128, 512, 256, 1024)):
    return [
        {
            "spp": s,
            "mean_var_left_all": a,
            "mean_var_left_glass": g,
            "mean_var_left_non_glass": n,
            "rho_all": 0.78,
            "rho_glass": 0.3,
            "rho_non_glass": 0.79,
        }
        for s, a, g, n in zip(spps, values_all, values_glass, values_non_glass, strict=True)
    ]


def test_sweep_rows_are_sorted_and_slopes_are_exact():
    spps = np.array([2048, 128, 512, 256, 1024], dtype=float)
    entries = sweep(1.0 / spps, 17.0 * spps**-0.8, 3e5 / spps)
    rows, fit = spp_sweep_table(entries)
    assert [r["spp"] for r in rows] == [128, 256, 512, 1024, 2048]
    assert fit["all"]["slope"] == pytest.approx(-1.0, abs=1e-12)
    assert fit["all"]["intercept"] == pytest.approx(0.0, abs=1e-10)
    assert fit["glass"]["slope"] == pytest.approx(-0.8, abs=1e-12)
    assert fit["glass"]["intercept"] == pytest.approx(math.log(17.0), abs=1e-10)
    assert fit["non_glass"]["slope"] == pytest.approx(-1.0, abs=1e-12)
    for f in fit.values():
        assert f["r2"] == pytest.approx(1.0) and f["n_points"] == 5 and f["reason"] == ""
    assert entries[0]["spp"] == 2048  # the input is not modified


def test_sweep_fit_by_hand_with_noise():
    spps = np.array([128, 256, 512], dtype=float)
    values = np.exp(np.array([0.0, -1.0, -1.5]))
    _, fit = spp_sweep_table(sweep(values, values, values, spps=spps.astype(int)))
    x = np.log(spps)
    slope = -1.5 / (2 * math.log(2))  # least squares through (x0, 0), (x1, -1), (x2, -1.5)
    assert fit["all"]["slope"] == pytest.approx(slope)
    assert fit["all"]["intercept"] == pytest.approx(-2.5 / 3 - slope * x.mean())
    residuals = np.log(values) - fit["all"]["intercept"] - slope * x
    ss_tot = ((np.log(values) - np.log(values).mean()) ** 2).sum()
    assert fit["all"]["r2"] == pytest.approx(1 - (residuals**2).sum() / ss_tot)


def test_sweep_skips_nan_and_missing_values():
    spps = np.array([128, 256, 512], dtype=float)
    entries = sweep(1 / spps, [NAN, 2.0, NAN], 4 / spps, spps=spps.astype(int))
    entries[2]["mean_var_left_non_glass"] = NAN
    for e in entries:
        del e["mean_var_left_all"]
    _, fit = spp_sweep_table(entries)
    assert fit["non_glass"]["slope"] == pytest.approx(-1.0) and fit["non_glass"]["n_points"] == 2
    for region in ("all", "glass"):
        assert math.isnan(fit[region]["slope"]) and fit[region]["reason"].startswith("fewer than 2")
    assert fit["glass"]["n_points"] == 1 and fit["all"]["n_points"] == 0


def test_sweep_rejects_duplicate_spp():
    with pytest.raises(ValueError, match="distinct"):
        spp_sweep_table(sweep([1, 1], [1, 1], [1, 1], spps=(128, 128)))
