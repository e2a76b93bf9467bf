"""Eq. 3: Pearson over a mask with Fisher-z interval and test; per-scene correlation rows."""

import math

import numpy as np
import pytest
import xarray as xr
from scipy import stats

from stereovar.statistics.correlation import pearson_over_mask
from stereovar.statistics.regions import region_masks
from stereovar.statistics.registry import METHODS

from .reference.correlation import correlation_rows

FIELD_METHODS = ("warp", "spearman", "log", "trimmed", "no_warp")
"""Statistics of the two variance fields alone (the controls need the job's inputs)."""

Z = 1.959963984540054


def fisher_reference(r, n):
    """Closed forms written out independently of the module."""
    z = 0.5 * math.log((1 + r) / (1 - r))
    se = 1 / math.sqrt(n - 3)
    stat = abs(z) * math.sqrt(n - 3)
    p = math.erfc(stat / math.sqrt(2))  # = 2 * Phi(-stat)
    return math.tanh(z - Z * se), math.tanh(z + Z * se), p


def test_rho_matches_scipy_and_fisher_closed_forms():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(40, 50))
    b = 0.3 * a + rng.normal(size=(40, 50))
    mask = rng.random((40, 50)) > 0.4
    out = pearson_over_mask(a, b, mask)
    ref = stats.pearsonr(a[mask], b[mask])
    assert out["n_pixels"] == int(mask.sum()) and out["n_nonfinite"] == 0
    assert out["reason"] == ""
    assert out["rho"] == pytest.approx(ref.statistic, abs=1e-12)
    lo, hi, p = fisher_reference(out["rho"], out["n_pixels"])
    assert out["fisher_low"] == pytest.approx(lo, rel=1e-12)
    assert out["fisher_high"] == pytest.approx(hi, rel=1e-12)
    assert out["p_value"] == pytest.approx(p, rel=1e-9)
    assert out["log10_p_value"] == pytest.approx(math.log10(p), rel=1e-9)
    # the Fisher test and the exact t test agree roughly for large n
    assert math.log10(out["p_value"]) == pytest.approx(math.log10(ref.pvalue), rel=0.1)


def test_log10_p_value_survives_underflow():
    rng = np.random.default_rng(1)
    a = rng.normal(size=200_000)
    b = a + 0.5 * rng.normal(size=200_000)
    out = pearson_over_mask(a, b, np.ones(a.shape, bool))
    assert out["p_value"] == 0.0
    z = math.atanh(out["rho"]) * math.sqrt(out["n_pixels"] - 3)
    # asymptotic log survival function of the normal: -z^2/2 - log(z sqrt(2 pi))
    approx = (-(z**2) / 2 - math.log(z * math.sqrt(2 * math.pi)) + math.log(2)) / math.log(10)
    assert math.isfinite(out["log10_p_value"])
    assert out["log10_p_value"] == pytest.approx(approx, rel=1e-6)


def test_known_correlation_of_jointly_gaussian_fields():
    rng = np.random.default_rng(2)
    n = 200_000
    x = rng.standard_normal(n)
    y = 0.6 * x + math.sqrt(1 - 0.36) * rng.standard_normal(n)
    out = pearson_over_mask(x.reshape(400, 500), y.reshape(400, 500), np.ones((400, 500), bool))
    assert abs(out["rho"] - 0.6) < 0.01
    assert out["fisher_low"] < 0.6 < out["fisher_high"]


def test_large_offset_and_scale_are_accurate():
    rng = np.random.default_rng(3)
    a = rng.normal(size=1000)
    b = a + rng.normal(size=1000)
    ref = pearson_over_mask(a, b, np.ones(1000, bool))["rho"]
    out = pearson_over_mask(1e8 + 1e-3 * a, 1e160 * b, np.ones(1000, bool))["rho"]
    assert out == pytest.approx(ref, abs=1e-4)  # squares of 1e160 would overflow


def test_too_few_pixels_and_constant_fields_are_nan_with_reason():
    rng = np.random.default_rng(4)
    a, b = rng.normal(size=(10, 10)), rng.normal(size=(10, 10))
    mask = np.zeros((10, 10), bool)
    mask[0, :9] = True
    out = pearson_over_mask(a, b, mask)
    assert out["reason"] == "fewer than 30 valid pixels (n=9)" and out["n_pixels"] == 9
    assert all(math.isnan(out[k]) for k in ("rho", "fisher_low", "fisher_high", "p_value"))
    out = pearson_over_mask(np.full((10, 10), 0.1), b, np.ones((10, 10), bool))
    assert out["reason"] == "constant field in region" and math.isnan(out["rho"])
    assert out["n_pixels"] == 100


def test_non_finite_values_inside_the_mask_are_excluded_and_counted():
    rng = np.random.default_rng(5)
    a, b = rng.normal(size=(20, 20)), rng.normal(size=(20, 20))
    a[0, 0], b[1, 1], b[2, 2] = np.nan, np.inf, -np.inf
    a[19, 19] = np.nan
    mask = np.ones((20, 20), bool)
    mask[19, 19] = False
    out = pearson_over_mask(a, b, mask)
    keep = mask & np.isfinite(a) & np.isfinite(b)
    assert out["n_nonfinite"] == 3 and out["n_pixels"] == 396
    assert out["rho"] == pytest.approx(stats.pearsonr(a[keep], b[keep]).statistic, abs=1e-12)


def test_region_masks_split_omega_by_glass():
    glass = np.array([[True, False], [True, True]])
    omega = np.array([[True, True], [False, True]])
    masks = region_masks({"glass": glass}, omega)
    np.testing.assert_array_equal(masks["all"], omega)
    np.testing.assert_array_equal(masks["glass"], [[True, False], [False, True]])
    np.testing.assert_array_equal(masks["non_glass"], [[False, True], [False, False]])
    gt = xr.Dataset({"glass": (("x", "y"), glass.T)})
    xmasks = region_masks(gt, xr.DataArray(omega, dims=("y", "x")))
    assert xmasks["glass"].dims == ("y", "x")
    np.testing.assert_array_equal(xmasks["glass"].values, masks["glass"])
    with pytest.raises(ValueError, match="select one view"):
        region_masks(gt.expand_dims(view=["left"]), omega)


def smooth_field(height, width, seed):
    """A positive field with structure at several scales (a stand-in for a variance field)."""
    rng = np.random.default_rng(seed)
    x = np.arange(width)[None, :]
    y = np.arange(height)[:, None]
    field = np.zeros((height, width))
    for _ in range(12):
        fx, fy = rng.uniform(0.02, 0.3, 2)
        field += rng.uniform(0.2, 1) * np.sin(fx * x + rng.uniform(0, 6)) * np.cos(fy * y)
    return np.exp(field)


def stereo_pair(d, sign=1, height=60, width=120, glass=True):
    """sigma_R is sigma_L moved by the disparity: sigma_L(x) = sigma_R(x + s d)."""
    xs = np.arange(-40, width + 40)
    base = smooth_field(height, xs.size, seed=7)
    right = base[:, 40 : 40 + width]
    left = np.stack([np.interp(np.arange(width) + sign * d, xs, row) for row in base])
    disparity = np.full((height, width), float(d))
    g = np.zeros((height, width), bool)
    if glass:
        g[10:30, 20:60] = True
    gt = xr.Dataset(
        {
            "disparity": (("y", "x"), disparity),
            "valid": (("y", "x"), np.ones((height, width), bool)),
            "glass": (("y", "x"), g),
        }
    )
    return left, right, gt


@pytest.mark.parametrize(("d", "sign"), [(7.0, 1), (4.35, 1), (5.6, -1)])
def test_warp_recovers_a_shifted_field_and_no_warp_does_not(d, sign):
    left, right, gt = stereo_pair(d, sign)
    rows = correlation_rows(left, right, gt, sign=sign)
    assert [(r["region"], r["method"]) for r in rows] == [
        (region, method) for region in ("all", "non_glass", "glass") for method in METHODS.names()
    ]
    by = {(r["region"], r["method"]): r for r in rows}
    for region in ("all", "non_glass", "glass"):
        warp, no_warp = by[region, "warp"], by[region, "no_warp"]
        assert warp["reason"] == "" and warp["n_pixels"] == no_warp["n_pixels"] > 30
        assert warp["rho"] > 0.99
        assert no_warp["rho"] < warp["rho"] - 0.1
    assert (
        by["glass", "warp"]["n_pixels"] + by["non_glass", "warp"]["n_pixels"]
        == (by["all", "warp"]["n_pixels"])
    )
    # pixels whose correspondence leaves the right image are not in omega
    assert by["all", "warp"]["n_pixels"] == 60 * (120 - math.ceil(d))


def test_opposite_sign_breaks_the_alignment():
    left, right, gt = stereo_pair(6.0, 1)
    good = correlation_rows(left, right, gt, sign=1)[0]["rho"]
    bad = correlation_rows(left, right, gt, sign=-1)[0]["rho"]
    assert good > 0.99 and bad < good - 0.1


def test_scene_without_glass_gives_nan_glass_rows():
    left, right, gt = stereo_pair(5.0, glass=False)
    rows = correlation_rows(left, right, gt, sign=1)
    for row in (r for r in rows if r["method"] in FIELD_METHODS):
        if row["region"] == "glass":
            assert math.isnan(row["rho"]) and row["reason"] == "no glass pixels in the scene"
        else:
            assert row["rho"] == row["rho"] and row["reason"] == ""


def test_non_finite_variance_is_excluded_and_counted():
    left, right, gt = stereo_pair(3.5)
    clean = {(r["region"], r["method"]): r for r in correlation_rows(left, right, gt, sign=1)}
    left, right = left.copy(), right.copy()
    left[40, 90] = np.nan  # non-glass
    finite_left = np.ones(left.shape, bool)
    finite_left[50, 100] = False  # flagged by the variance store; value 0 there
    left[50, 100] = 0.0
    right[15, 50] = np.inf  # glass; a neighbour of the warped values of left x = 46 and 47
    rows = correlation_rows(left, right, gt, sign=1, finite_left=finite_left)
    by = {(r["region"], r["method"]): r for r in rows}
    assert by["all", "warp"]["n_nonfinite"] == 4
    assert by["non_glass", "warp"]["n_nonfinite"] == 2
    assert by["glass", "warp"]["n_nonfinite"] == 2
    assert by["all", "warp"]["n_pixels"] == clean["all", "warp"]["n_pixels"] - 4
    # the unaligned right value at (15, 50) is non-finite too: one more for no_warp
    assert by["glass", "no_warp"]["n_nonfinite"] == 3
    for row in (r for r in rows if r["method"] in FIELD_METHODS):
        assert math.isfinite(row["rho"]) and row["rho"] == pytest.approx(
            clean[row["region"], row["method"]]["rho"], abs=0.01
        )


def test_xarray_fields_are_accepted_in_any_dim_order():
    left, right, gt = stereo_pair(4.5)
    rows_np = correlation_rows(left, right, gt, sign=1)
    rows_xr = correlation_rows(
        xr.DataArray(left, dims=("y", "x")).T, xr.DataArray(right, dims=("y", "x")), gt, sign=1
    )
    for a, b in zip(rows_np, rows_xr, strict=True):
        assert a["rho"] == pytest.approx(b["rho"], abs=1e-12, nan_ok=True)
        assert a["reason"] == b["reason"]


def test_a_neighbour_with_zero_bilinear_weight_does_not_exclude_a_pixel():
    """At an integer disparity the warped value is one right pixel: only that one matters."""
    left, right, gt = stereo_pair(3.0)
    right = right.copy()
    right[15, 50] = np.nan  # the value of left x = 47; a zero-weight neighbour of x = 46
    finite_right = np.isfinite(right)
    rows = correlation_rows(left, np.nan_to_num(right), gt, sign=1, finite_right=finite_right)
    assert rows[0]["n_nonfinite"] == 1


@pytest.mark.parametrize("stat", [0.0, 0.5, 3.0, 10.0, 27.0, 28.5, 40.0, 200.0])
def test_log10_p_value_matches_scipy_without_underflow(stat):
    from scipy.special import log_ndtr

    from stereovar.statistics.correlation import log10_two_sided_normal_p

    expected = (log_ndtr(-stat) + np.log(2.0)) / np.log(10.0)
    assert log10_two_sided_normal_p(stat) == pytest.approx(expected, rel=1e-9, abs=1e-12)
    assert log10_two_sided_normal_p(-stat) == log10_two_sided_normal_p(stat)
