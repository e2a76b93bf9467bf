"""The results page's headline (stereovar.pages.results): the Monte Carlo-specific rho from
the run's summary and the calibration's matched nulls, against the mitigation table's scene by
scene computation, and the conclusion each verdict gives."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stereovar.pages.conclusion import conclusion
from stereovar.pages.headline import matched_headline
from stereovar.statistics.across import combined_interval
from stereovar.statistics.matched_null import matched_difference


def scenes(rng, n: int):
    """``n`` scenes' intensity-controlled rho rows and their matched nulls."""
    corr, nulls = [], []
    for i in range(n):
        rho = float(rng.uniform(-0.2, 0.8))
        corr.append({"scene": f"s{i}", "region": "all", "method": "partial", "rho": rho,
                     "boot_low": rho - float(rng.uniform(0.01, 0.1)),
                     "boot_high": rho + float(rng.uniform(0.01, 0.1))})
        nulls.append({"scene": f"s{i}", "transform": "none", "region": "all",
                      "method": "partial", "null_rho": float(rng.uniform(-0.05, 0.3)),
                      "null_se": float(rng.uniform(0, 0.02)),
                      "chance_sd": float(rng.uniform(0, 0.06)), "margin": 0.05})
    return corr, nulls


@pytest.mark.parametrize("n", [1, 2, 5])
def test_matched_headline_is_the_mitigation_tables_scene_by_scene_difference(n):
    rng = np.random.default_rng(n)
    corr, nulls = scenes(rng, n)
    # decoys: another transform, region and statistic, which must not count
    nulls += [{**nulls[0], "transform": "denoise", "null_rho": 0.9},
              {**nulls[0], "region": "glass", "null_rho": -0.9},
              {**nulls[0], "method": "warp", "null_rho": 0.5}]
    mean, low, high = combined_interval(*([r[k] for r in corr]
                                          for k in ("rho", "boot_low", "boot_high")))
    summary = [{"region": "all", "method": "partial", "mean_rho": mean, "boot_low": low,
                "boot_high": high, "n_scenes": n}]
    got = matched_headline(summary, nulls)
    null, diff, d_low, d_high = matched_difference(corr, nulls, transform="none", region="all")
    assert got["null"] == pytest.approx(null, abs=1e-12)
    assert (got["value"], got["low"], got["high"]) == pytest.approx((diff, d_low, d_high),
                                                                    abs=1e-9)


def test_matched_headline_without_a_null_is_not_a_number():
    summary = [{"region": "all", "method": "partial", "mean_rho": 0.5, "boot_low": 0.4,
                "boot_high": 0.6, "n_scenes": 2}]
    got = matched_headline(summary, [])
    assert math.isnan(got["value"]) and got["verdict"] == "n/a"
    # nulls of other scenes than the run's do not count
    other = [{"scene": "x", "transform": "none", "region": "all", "method": "partial",
              "null_rho": 0.1, "null_se": 0.0, "chance_sd": 0.0}]
    assert math.isnan(matched_headline(summary, other, scenes=["a", "b"])["value"])


@pytest.mark.parametrize(
    "low, high, word",
    [(0.3, 0.5, "Cue present"), (-0.02, 0.03, "No cue"), (-0.1, 0.2, "Undecided"),
     (-0.5, -0.3, "Below the null")],
)
def test_the_conclusion_word_follows_the_verdict_and_carries_the_number(low, high, word):
    summary = [{"region": "all", "method": "partial", "mean_rho": 0.2 + (low + high) / 2,
                "boot_low": 0.2 + low, "boot_high": 0.2 + high, "n_scenes": 1}]
    nulls = [{"scene": "a", "transform": "none", "region": "all", "method": "partial",
              "null_rho": 0.2, "null_se": 0.0, "chance_sd": 0.0, "margin": 0.05}]
    matched = matched_headline(summary, nulls)
    c = conclusion(matched, {"text": "0.7 [0.6, 0.8]"})
    assert c["word"] == word
    assert f"ρ = {(low + high) / 2:.3f} [{low:.3f}, {high:.3f}]" in c["text"]
    assert "matched null 0.200" in c["text"]


def test_without_a_null_the_conclusion_calls_nothing_monte_carlo_specific():
    c = conclusion(matched_headline([], []), {"text": "0.745 [0.622, 0.868]"},
                   {("all", "warp"): "ρ of a simulated camera's noise"})
    assert c["word"] == "Not calibrated" and "Monte Carlo-specific ρ =" not in c["text"]
    assert "0.745 [0.622, 0.868], explained by a control" in c["text"]
