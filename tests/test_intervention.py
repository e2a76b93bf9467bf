"""The Sec. 3.4 intervention on a synthetic pair with a known integer disparity."""

import numpy as np
import pytest

from stereovar.intervention import intervention_metrics

N, H, W, D0 = 6, 40, 72, 3


def shifted_pair(sign):
    """Right view = left view moved by D0 (x_R = x_L + sign * D0), seed by seed."""
    rng = np.random.default_rng(0)
    yy, xx = np.mgrid[0:H, 0 : W + D0]
    clean = 0.5 + 0.3 * np.sin(xx / 2.3) * np.cos(yy / 3.1)
    amp = 0.02 + 0.05 * (np.sin(xx / 5.0) ** 2) * (1 + yy / H)
    big = clean[None] + amp[None] * rng.standard_normal((N, H, W + D0))
    # sign = +1: R(x + D0) = L(x), so L(x) = B(x + D0) and R(x) = B(x).
    if sign == 1:
        left, right = big[:, :, D0:], big[:, :, :W]
    else:
        left, right = big[:, :, :W], big[:, :, D0:]
    glass = np.zeros((H, W), bool)
    glass[8:24, 16:40] = True
    gt = {"disparity": np.full((H, W), float(D0)), "valid": np.ones((H, W), bool), "glass": glass}
    return left, right, gt


@pytest.mark.parametrize("sign", [1, -1])
def test_aligned_residuals_win_and_the_shuffle_breaks_them(sign):
    left, right, gt = shifted_pair(sign)
    rows = intervention_metrics(left, right, gt, sign=sign, max_disparity=8, window=5, block=8)
    assert len(rows) == 5 * 2 * 2
    table = {(r["cost"], r["metric"], r["region"], r["condition"]): r for r in rows}
    for region in ("non_glass", "glass"):
        normal = table[("residual_sad", "wta_accuracy", region, "normal")]
        decorr = table[("residual_sad", "wta_accuracy", region, "decorrelated")]
        assert normal["value"] == 1.0
        assert decorr["value"] < 0.6
        assert normal["chance"] == pytest.approx(1 / 9, rel=0.3)
        m_normal = table[("residual_sad", "gt_margin", region, "normal")]["value"]
        m_decorr = table[("residual_sad", "gt_margin", region, "decorrelated")]["value"]
        assert m_normal > 0 > m_decorr
        assert table[("variance_cost", "wta_accuracy", region, "normal")]["value"] == 1.0
        assert table[("variance_cost", "gt_margin", region, "normal")]["value"] > 0
        peak = table[("variance_peak", "peak_hit_rate", region, "normal")]["value"]
        assert peak > table[("variance_peak", "peak_hit_rate", region, "decorrelated")]["value"]
    assert all(r["reason"] == "" for r in rows)


def test_region_without_pixels_is_nan_with_reason():
    left, right, gt = shifted_pair(1)
    gt["glass"][:] = False
    rows = intervention_metrics(left, right, gt, sign=1, max_disparity=8, window=5, block=8)
    glass = [r for r in rows if r["region"] == "glass"]
    assert glass and all(np.isnan(r["value"]) and "no scoreable" in r["reason"] for r in glass)
