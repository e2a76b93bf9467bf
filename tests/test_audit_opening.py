"""The verdict's opening and summary line quote the number the verdict rests on, the
intensity-controlled rho minus its matched null, beside that null; without a matched null
nothing is called Monte Carlo-specific."""

import pytest

from stereovar.audit.decision import decision
from stereovar.audit.verdict import SPECIFIC, summary_lines, verdict, verdict_rows


def corr_row(scene, method, rho, low, high):
    return {"scene": scene, "region": "all", "method": method, "rho": rho, "boot_low": low,
            "boot_high": high, "reliability_left": 0.81, "reliability_right": 0.81,
            "rho_corrected": rho / 0.81}


def correlations():
    """Two frames: intensity-controlled rho 0.60 and 0.62, Pearson 0.5, camera 0.45."""
    rows = []
    for scene, partial in (("a", 0.60), ("b", 0.62)):
        rows.append(corr_row(scene, "partial", partial, partial - 0.05, partial + 0.05))
        for method, rho in (("warp", 0.5), ("sensor_sim", 0.45), ("null_shift", 0.0)):
            rows.append(corr_row(scene, method, rho, rho - 0.05, rho + 0.05))
    return rows


NULLS = [
    {"scene": s, "transform": "none", "region": "all", "method": "partial", "null_rho": 0.10,
     "null_se": 0.0, "chance_sd": 0.0}
    for s in ("a", "b")
]


def test_with_a_matched_null_the_opening_quotes_the_difference_beside_it():
    rows = verdict_rows(correlations(), [], NULLS)
    specific = next(r for r in rows if r["quantity"] == SPECIFIC and r["region"] == "all")
    assert specific["value"] == pytest.approx(0.51) and specific["null"] == pytest.approx(0.10)
    result = verdict(rows)
    assert result["matched_null"] is True and result["mc_specific"] is True
    sure = decision(result, {"shared": False}, [], [], rows)["sentences"][0]
    low, high = specific["low"], specific["high"]
    assert f"the Monte Carlo-specific rho is 0.510 [{low:.3f}, {high:.3f}]" in sure
    assert "minus its matched null 0.100" in sure
    first = summary_lines("t", "2 frames", rows, result)[0]
    assert f"Monte Carlo-specific rho 0.510 [{low:.3f}, {high:.3f}]" in first
    assert "minus its matched null 0.100" in first


def test_without_a_matched_null_nothing_is_called_monte_carlo_specific():
    rows = verdict_rows(correlations(), [])
    result = verdict(rows)
    assert result["matched_null"] is False and result["mc_specific"] is True
    opening = decision(result, {"shared": False}, [], [], rows)
    first = summary_lines("t", "2 frames", rows, result)[0]
    for text in (opening["headline"], result["text"].split(".")[0], first):
        assert "Monte Carlo-specific cue" not in text.replace("not tested as Monte Carlo", "")
    assert "not tested as Monte Carlo-specific" in opening["headline"]
    assert "intensity-controlled rho 0.610" in first and "(no matched null)" in first
    assert not any(r["quantity"] == SPECIFIC for r in rows)
