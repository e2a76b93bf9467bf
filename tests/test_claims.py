"""The claims table: its verdict rule on synthetic per-scene values with known intervals, the
log-scale interval of ratio claims, and the claims file it is built from."""

from __future__ import annotations

import hashlib
import json
import math

import numpy as np
import pytest
import yaml
from scipy import stats

from stereovar.errors import ClaimsError
from stereovar.io.tables import read_rows, write_tables
from stereovar.statistics.claim_rules import (
    EXPLAINED,
    FAILS,
    HOLDS,
    UNTESTABLE,
    verdict,
)
from stereovar.statistics.claim_statistics import STATISTICS
from stereovar.statistics.claims import CLAIMS_PATH, claims_table, load_claims
from stereovar.statistics.t_intervals import geometric_t_interval

S = 4
"""Scenes of the synthetic runs."""


def correlation_rows(rho, half, *, method="warp", region="all", glass=None, non_glass=1.0):
    """S scenes' rows of one (region, method): scene s has ``rho[s]`` with the bootstrap
    interval rho +- ``half``, and ``mean_a`` ``glass[s]`` / ``non_glass`` when given.
    :func:`scenes_interval` of ``rho`` is the known answer of these tests."""
    rows = []
    for s, r in enumerate(rho):
        rows.append(
            {
                "scene": f"scene_{s:03d}",
                "region": region,
                "method": method,
                "rho": r,
                "boot_low": r - half,
                "boot_high": r + half,
                "mean_a": math.nan if glass is None else glass[s],
            }
        )
    return rows


def scenes_interval(rho, level=0.95):
    """The interval for the mean rho over scenes like these, by hand: the Student-t interval
    of the scene values (their spread holds the between-scene variance and each scene's
    error), taken on Fisher's z = atanh(rho) about the mean rho's z and mapped back with
    tanh, so that it stays inside [-1, 1]."""
    rho = np.asarray(rho, dtype=np.float64)
    half = stats.t.ppf(0.5 + level / 2, rho.size - 1) * stats.sem(np.arctanh(rho))
    centre = np.arctanh(rho.mean())
    return np.tanh(centre - half), np.tanh(centre + half)


def ratio_rows(glass, non_glass):
    """Warp rows of the glass and non-glass regions with per-scene mean variances."""
    rows = []
    for s, (g, n) in enumerate(zip(glass, non_glass, strict=True)):
        for region, mean in (("glass", g), ("non_glass", n)):
            rows.append(
                {
                    "scene": f"scene_{s:03d}",
                    "region": region,
                    "method": "warp",
                    "rho": 0.5,
                    "boot_low": 0.4,
                    "boot_high": 0.6,
                    "mean_a": mean,
                }
            )
    return rows


def by_id(rows, **inputs):
    return {c["id"]: c for c in claims_table(rows, **inputs)}


def log_interval(ratios):
    """The geometric mean and the exponentiated 95% t interval of the logs, by scipy."""
    logs = np.log(np.asarray(ratios, dtype=np.float64))
    low, high = stats.t.interval(0.95, logs.size - 1, loc=logs.mean(), scale=stats.sem(logs))
    return math.exp(logs.mean()), math.exp(low), math.exp(high)


# ------------------------------------------------------------------------- the level rule


SPREAD = np.array([-3.0, -1.0, 1.0, 3.0])
"""Scene offsets with mean 0 and SD sqrt(20 / 3): scaled by k, the 95% t interval over the
S = 4 scenes is the mean +- t_{0.975,3} k sqrt(20 / 3) / 2 = +- 4.11 k on the scale of rho,
about +- 4.11 k / (1 - rho^2) on Fisher's z (the delta method; the claims' interval)."""


@pytest.mark.parametrize(
    ("rho_mean", "k", "sensor", "expected"),
    [
        # [-0.08, 0.78]: contains 0.754 and 0, so the claim cannot be told from no effect
        (0.45, 0.1, 0.1, UNTESTABLE),
        # [0.71, 0.79]: contains 0.754, excludes 0, the sensor's [0.06, 0.14] far below it
        (0.75, 0.01, 0.1, HOLDS),
        # the same, with a sensor at [0.68, 0.76]: ours minus it, 0.03 +- 0.06, reaches 0
        (0.75, 0.01, 0.72, EXPLAINED),
        # [0.12, 0.28]: excludes the paper's value and the null
        (0.2, 0.02, 0.1, FAILS),
        # [-0.11, 0.30]: contains the null but not the paper's value, which it rules out
        (0.1, 0.05, 0.1, FAILS),
    ],
)
def test_level_claim_holds_only_with_the_paper_inside_and_the_null_outside(
    rho_mean, k, sensor, expected
):
    """The interval is for the mean over scenes like these: the scenes' spread sets it, and
    their bootstrap half-widths (0.05 here) do not enter."""
    ours, theirs = rho_mean + k * SPREAD, sensor + 0.01 * SPREAD
    rows = correlation_rows(ours, 0.05) + correlation_rows(theirs, 0.05, method="sensor_sim")
    row = by_id(rows)["rho_all"]
    assert row["ours"] == pytest.approx(rho_mean)
    low, high = scenes_interval(ours)
    assert (row["ours_low"], row["ours_high"]) == pytest.approx((low, high))
    normal = stats.t.interval(0.95, S - 1, loc=rho_mean, scale=stats.sem(ours))
    assert normal[1] - rho_mean == pytest.approx(4.11 * k, rel=1e-3)
    half_z = (np.arctanh(high) - np.arctanh(low)) / 2
    assert half_z == pytest.approx(4.11 * k / (1 - rho_mean**2), rel=0.1)
    assert -1 < low < rho_mean < high < 1
    assert row["control_high"] == pytest.approx(scenes_interval(theirs)[1])
    assert row["null"] == 0.0
    assert row["verdict"] == expected


def test_a_claim_that_the_value_is_the_null_is_decided_by_equivalence():
    """Real sensors' rho = 0 is the null itself: an interval that must exclude the null
    cannot confirm it, so the claim has a margin and holds when the 90% interval lies inside
    it (two one-sided tests at 5%)."""
    margin = 0.1
    for k, expected in ((0.04, UNTESTABLE), (0.01, HOLDS)):
        sensor = k * SPREAD
        low90, high90 = scenes_interval(sensor, level=0.90)
        inside = -margin < low90 and high90 < margin
        assert inside == (expected == HOLDS)  # +-0.12 and +-0.03 against 0.1
        row = by_id(correlation_rows(sensor, 0.05, method="sensor_sim"))["real_sensors_rho_zero"]
        assert row["verdict"] == expected
    far = 0.6 + 0.04 * SPREAD
    assert scenes_interval(far)[0] > margin
    row = by_id(correlation_rows(far, 0.05, method="sensor_sim"))["real_sensors_rho_zero"]
    assert row["verdict"] == FAILS


def test_verdict_rule_on_intervals():
    nan3 = (math.nan,) * 3
    # ratio: null 1 by default
    assert verdict("ratio", 7.0, 6.5, 0.9, 45.0) == UNTESTABLE
    assert verdict("ratio", 7.0, 6.5, 1.1, 45.0) == HOLDS
    assert verdict("ratio", 7.0, 2.0, 1.5, 3.0) == FAILS
    assert verdict("ratio", 7.0, 0.5, 0.2, 0.9) == FAILS
    # level: the claim's own null
    assert verdict("level", 0.5, 0.5, 0.3, 0.7, null_value=0.4) == UNTESTABLE
    assert verdict("level", 0.5, 0.5, 0.3, 0.7) == HOLDS
    # an undefined interval
    assert verdict("ratio", 7.0, 7.0, math.nan, math.nan) == UNTESTABLE
    # tolerance: the paper's value is the tolerance, decided by equivalence on the interval
    assert verdict("tolerance", 0.01, -0.009, -0.0095, -0.0085) == HOLDS
    assert verdict("tolerance", 0.01, -0.009, -0.012, -0.006) == UNTESTABLE
    assert verdict("tolerance", 0.01, 0.011, 0.0105, 0.0115) == FAILS
    assert verdict("tolerance", 0.01, -0.009, *nan3[:2]) == UNTESTABLE  # no interval
    with pytest.raises(ValueError, match="unknown claim kind"):
        verdict("band", 1.0, 1.0, 0.0, 2.0)


# ------------------------------------------------------------------------- ratio claims


def test_a_skewed_variance_ratio_is_not_testable_on_the_log_scale():
    """Per-scene ratios whose arithmetic t interval contains 7, 1 and negative values (which
    a variance ratio cannot take): the log-scale interval contains 7 and 1, so the claim is
    not testable rather than holding."""
    ratios = np.array([1.5, 4.0, 12.0, 24.42])
    arithmetic = stats.t.interval(0.95, S - 1, loc=ratios.mean(), scale=stats.sem(ratios))
    assert arithmetic[0] < 0 < 1 < 7 < arithmetic[1]  # the arithmetic rule said "holds"
    row = by_id(ratio_rows(ratios, np.ones(S)))["glass_variance_ratio"]
    gm, low, high = log_interval(ratios)
    assert (row["ours"], row["ours_low"], row["ours_high"]) == pytest.approx((gm, low, high))
    assert row["ours"] == pytest.approx(stats.gmean(ratios))
    assert 0 < low < 1 < 7 < high
    assert row["kind"] == "ratio" and row["null"] == 1.0
    assert row["verdict"] == UNTESTABLE


@pytest.mark.parametrize(
    ("ratios", "expected"),
    [
        ([6.0, 7.5, 8.0, 7.0], HOLDS),  # about 7, well above 1
        ([1.8, 2.2, 2.0, 2.1], FAILS),  # well above 1 but far below 7
        ([0.4, 0.6, 0.5, 0.55], FAILS),  # below 1: glass is the quieter region
        ([0.3, 3.0, 40.0, 9.0], UNTESTABLE),  # contains 1 and 7
    ],
)
def test_ratio_claim_verdict_on_the_log_scale(ratios, expected):
    non_glass = np.array([600.0, 0.5, 3.0, 1e-3])  # the ratio, not the level, is tested
    row = by_id(ratio_rows(np.asarray(ratios) * non_glass, non_glass))["glass_variance_ratio"]
    gm, low, high = log_interval(ratios)
    assert (row["ours"], row["ours_low"], row["ours_high"]) == pytest.approx((gm, low, high))
    inside = low <= 7.0 <= high
    null_inside = low <= 1.0 <= high
    want = FAILS if not inside else UNTESTABLE if null_inside else HOLDS
    assert want == expected
    assert row["verdict"] == expected


def test_geometric_t_interval_against_brute_force_logs():
    rng = np.random.default_rng(7)
    for size in (2, 3, 5, 20):
        ratios = np.exp(rng.normal(1.5, 0.8, size))
        logs = np.log(ratios)
        half = stats.t.ppf(0.975, size - 1) * np.sqrt(
            ((logs - logs.mean()) ** 2).sum() / (size - 1)
        )
        half /= np.sqrt(size)
        want = np.exp([logs.mean(), logs.mean() - half, logs.mean() + half])
        assert geometric_t_interval(ratios) == pytest.approx(tuple(want), rel=1e-12)
        # a ratio and its inverse: the same interval, inverted
        gm, low, high = geometric_t_interval(1 / ratios)
        assert (gm, low, high) == pytest.approx((1 / want[0], 1 / want[2], 1 / want[1]), rel=1e-12)
    # equal ratios: that ratio, with a zero-width interval (the spread of the logs is 0)
    for size in (2, 3, 7):
        assert geometric_t_interval([7.0] * size) == (7.0, 7.0, 7.0)
        assert verdict("ratio", 7.0, *geometric_t_interval([7.0] * size)) == HOLDS
    one = geometric_t_interval([3.0])
    assert one[0] == pytest.approx(3.0) and math.isnan(one[1]) and math.isnan(one[2])
    assert all(math.isnan(v) for v in geometric_t_interval([]))


@pytest.mark.parametrize("bad", [0.0, -2.0, math.inf, math.nan])
def test_geometric_t_interval_refuses_a_ratio_without_a_logarithm(bad):
    with pytest.raises(ValueError, match="has no logarithm"):
        geometric_t_interval([2.0, bad, 3.0])


@pytest.mark.parametrize(
    ("glass", "non_glass", "named"),
    [
        ([7.0, 0.0, 6.0, 8.0], [1.0, 1.0, 1.0, 1.0], "scene_001 (glass 0, non_glass 1)"),
        ([7.0, 6.0, -3.0, 8.0], [1.0, 1.0, 1.0, 1.0], "scene_002 (glass -3, non_glass 1)"),
        ([7.0, 6.0, 5.0, 8.0], [1.0, 0.0, 1.0, 1.0], "scene_001 (glass 6, non_glass 0)"),
    ],
)
def test_a_scene_with_a_non_positive_ratio_makes_the_ratio_claim_not_testable(
    glass, non_glass, named
):
    """No geometric mean of the other scenes: dropping the scene would hide it."""
    row = by_id(ratio_rows(glass, non_glass))["glass_variance_ratio"]
    assert all(math.isnan(row[k]) for k in ("ours", "ours_low", "ours_high"))
    assert row["verdict"] == UNTESTABLE
    assert named in row["note"] and "no logarithm" in row["note"]


def test_a_scene_without_glass_is_left_out_of_the_ratio_and_named():
    glass = [7.0, math.nan, 6.0, 8.0]  # scene_001 has no glass pixels
    row = by_id(ratio_rows(glass, [1.0] * 4))["glass_variance_ratio"]
    gm, low, high = log_interval([7.0, 6.0, 8.0])
    assert (row["ours"], row["ours_low"], row["ours_high"]) == pytest.approx((gm, low, high))
    assert row["note"] == "left out, no finite mean_a: scene_001"
    assert row["verdict"] == HOLDS


# ------------------------------------------------------------------------- the claims file


def test_every_claim_in_the_file_is_a_row_and_every_row_is_a_claim_of_the_file():
    raw = yaml.safe_load(CLAIMS_PATH.read_text(encoding="utf-8"))
    table = claims_table([])
    assert [r["id"] for r in table] == [c["id"] for c in raw["claims"]]
    for row, claim in zip(table, raw["claims"], strict=True):
        assert row["claim"] == claim["text"]
        assert row["paper"] == claim["paper"]
        assert row["kind"] == claim["kind"]
        assert row["section"] == claim["section"]
        assert row["control"] == (claim["control"] or {}).get("label", "")
    # the statistics the file names are the ones the code computes, and each one is used
    named = {c[part]["name"] for c in raw["claims"] for part in ("statistic",)}
    named |= {c["control"]["statistic"]["name"] for c in raw["claims"] if c["control"]}
    assert named == set(STATISTICS)


def test_the_table_takes_the_paper_values_from_the_file(tmp_path):
    """Change a claim's value and drop another in a copy: the table follows the copy."""
    raw = yaml.safe_load(CLAIMS_PATH.read_text(encoding="utf-8"))
    raw["claims"] = [c for c in raw["claims"] if c["id"] != "rho_no_warp"]
    first = next(c for c in raw["claims"] if c["id"] == "rho_all")
    first["paper"], first["text"] = 0.4, "rho (all) = 0.4"
    path = tmp_path / "claims.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    spread = np.array([-0.03, -0.01, 0.01, 0.03])
    rows = correlation_rows(0.4 + spread, 0.1)  # [0.36, 0.44]
    table = {c["id"]: c for c in claims_table(rows, claims=load_claims(path))}
    assert "rho_no_warp" not in table and len(table) == len(raw["claims"])
    assert table["rho_all"]["claim"] == "rho (all) = 0.4"
    assert table["rho_all"]["verdict"] == HOLDS
    # the paper's file says 0.754, outside [0.35, 0.45]
    assert by_id(rows)["rho_all"]["verdict"] == FAILS


def test_the_file_records_the_digest_of_its_bytes():
    claims = load_claims()
    assert claims.sha256 == hashlib.sha256(CLAIMS_PATH.read_bytes()).hexdigest()
    caption = claims.caption()
    for kind in ("level", "ratio", "direction", "tolerance"):
        assert claims.rules[kind] in caption
    assert claims.intervals in caption


def _mutated(tmp_path, change) -> str:
    raw = yaml.safe_load(CLAIMS_PATH.read_text(encoding="utf-8"))
    change(raw)
    path = tmp_path / "claims.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    return path


def _claim(raw, claim_id):
    return next(c for c in raw["claims"] if c["id"] == claim_id)


def _set(claim_id, *keys, value):
    def change(raw):
        node = _claim(raw, claim_id)
        for key in keys[:-1]:
            node = node[key]
        node[keys[-1]] = value

    return change


def _drop(claim_id, *keys):
    def change(raw):
        node = _claim(raw, claim_id)
        for key in keys[:-1]:
            node = node[key]
        del node[keys[-1]]

    return change


@pytest.mark.parametrize(
    ("change", "key", "problem"),
    [
        (_drop("rho_glass", "paper"), "claims[2] (rho_glass)", "'paper' is a required property"),
        (_set("rho_glass", "paper", value="0.301"), "claims[2] (rho_glass).paper", "type"),
        (_set("rho_glass", "paper", value=math.nan), "claims[2] (rho_glass).paper", "finite"),
        (_set("rho_glass", "kind", value="band"), "claims[2] (rho_glass).kind", "band"),
        (_set("rho_glass", "id", value="rho_all"), "claims[2] (rho_all).id", "claims[0]"),
        (_set("rho_glass", "bogus", value=1), "claims[2] (rho_glass)", "bogus"),
        (_drop("rho_glass", "rule", "null_value"), "claims[2] (rho_glass).rule", "null_value"),
        (
            _set("rho_glass_below_non_glass", "rule", "null_value", value=0.0),
            "claims[3] (rho_glass_below_non_glass).rule.null_value",
            "remove it",
        ),
        (
            _set("glass_variance_ratio", "paper", value=-7.0),
            "claims[7] (glass_variance_ratio).paper",
            "> 0",
        ),
        (
            _set("glass_variance_ratio", "statistic", "name", value="ratio"),
            "claims[7] (glass_variance_ratio).statistic.name",
            "unknown statistic 'ratio'",
        ),
        (
            _set("glass_variance_ratio", "statistic", "numerator", value="metal"),
            "claims[7] (glass_variance_ratio).statistic.numerator",
            "'metal' is not allowed",
        ),
        (
            _drop("glass_variance_ratio", "statistic", "column"),
            "claims[7] (glass_variance_ratio).statistic",
            "needs the setting 'column'",
        ),
        (
            _set("rho_all", "control", "statistic", "region", value="outdoors"),
            "claims[0] (rho_all).control.statistic.region",
            "'outdoors' is not allowed",
        ),
        (
            _set(
                "table3_variance_peak_peak_hit_rate_glass",
                "statistic",
                "metric",
                value="gt_margin",
            ),
            "claims[18] (table3_variance_peak_peak_hit_rate_glass).statistic",
            "not reported for cost 'variance_peak'",
        ),
        (
            _set(
                "table3_residual_sad_gt_margin_glass",
                "control",
                "statistic",
                "source",
                value="render",
            ),
            "claims[10] (table3_residual_sad_gt_margin_glass).control.statistic",
            "the claim's own statistic",
        ),
        (
            _drop("real_sensors_rho_zero", "rule", "equivalence_margin"),
            "claims[8] (real_sensors_rho_zero).rule",
            "give equivalence_margin",
        ),
        (
            _set("real_sensors_rho_zero", "rule", "equivalence_margin", value=0.0),
            "claims[8] (real_sensors_rho_zero).rule.equivalence_margin",
            "less than or equal to the minimum of 0",
        ),
        (
            _set("real_sensors_rho_zero", "rule", "control_explains", value=True),
            "claims[8] (real_sensors_rho_zero).rule",
            "set control_explains: false",
        ),
        (
            _set("rho_glass_below_non_glass", "rule", "equivalence_margin", value=0.1),
            "claims[3] (rho_glass_below_non_glass).rule.equivalence_margin",
            "a direction claim has no equivalence_margin",
        ),
        (
            _set("spp_invariance", "rule", "equivalence_margin", value=0.1),
            "claims[5] (spp_invariance).rule.equivalence_margin",
            "its margin is its tolerance",
        ),
        (
            _set("glass_variance_ratio", "paper", value=1.0),
            "claims[7] (glass_variance_ratio).paper",
            "could never hold",
        ),
        (
            _set("rho_no_warp", "rule", "control_share", value=0.5),
            "claims[4] (rho_no_warp).rule.control_share",
            "needs a control that can explain",
        ),
        (
            _set("rho_all", "rule", "control_share", value=1.5),
            "claims[0] (rho_all).rule.control_share",
            "greater than the maximum of 1",
        ),
        (lambda raw: raw["rules"].pop("ratio"), "rules", "'ratio' is a required property"),
        (lambda raw: raw.update(extra=1), "(top level)", "extra"),
    ],
)
def test_a_malformed_claims_file_is_one_line_naming_the_key(tmp_path, change, key, problem):
    path = _mutated(tmp_path, change)
    with pytest.raises(ClaimsError) as err:
        load_claims(path)
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: {key}: ")
    assert problem in message and message.endswith("fix that key")


def test_a_claims_file_that_is_missing_or_not_yaml_is_one_line(tmp_path):
    with pytest.raises(ClaimsError, match="cannot be read") as err:
        load_claims(tmp_path / "absent.yaml")
    assert "\n" not in str(err.value)
    bad = tmp_path / "claims.yaml"
    bad.write_text("rules: [unclosed\n")
    with pytest.raises(ClaimsError, match="is not valid YAML") as err:
        load_claims(bad)
    assert "\n" not in str(err.value)


# ------------------------------------------------------------------------- the job


def _write_inputs(tmp_path, ratios):
    columns = [
        "scene",
        "spp",
        "n_seeds",
        "region",
        "method",
        "rho",
        "boot_low",
        "boot_high",
        "fisher_low",
        "fisher_high",
        "mean_a",
        "rho_corrected",
    ]
    paths = []
    for s, ratio in enumerate(ratios):
        rows = []
        for region, mean in (("all", 2.0), ("non_glass", 1.0), ("glass", ratio)):
            rows.append(
                {
                    "scene": f"scene_{s:03d}",
                    "spp": 8,
                    "n_seeds": 4,
                    "region": region,
                    "method": "warp",
                    "rho": 0.5,
                    "boot_low": 0.45,
                    "boot_high": 0.55,
                    "fisher_low": 0.48,
                    "fisher_high": 0.52,
                    "mean_a": mean,
                    "rho_corrected": 0.6,
                }
            )
        path = tmp_path / f"scene_{s:03d}.csv"
        write_tables(rows, columns, {"csv": path})
        paths.append(str(path))
    return paths


def test_claims_job_states_the_rule_and_records_the_claims_file(tmp_path):
    from stereovar.jobs.claims import claims_job

    ratios = [1.5, 4.0, 12.0, 24.42]
    outputs = {k: tmp_path / f"claims.{k}" for k in ("csv", "md")}
    kwargs = dict(
        correlations=_write_inputs(tmp_path, ratios),
        curves=[],
        sweep="",
        interventions=[],
        outputs=outputs,
        summary=tmp_path / "summary.json",
        spp=8,
    )
    stale = "0" * 64
    with pytest.raises(ClaimsError, match="changed after the workflow was read"):
        claims_job(**kwargs, claims_digest=stale)
    assert not any(p.exists() for p in [*outputs.values(), tmp_path / "summary.json"])

    digest = hashlib.sha256(CLAIMS_PATH.read_bytes()).hexdigest()
    claims_job(**kwargs, claims_digest=digest)
    md = outputs["md"].read_text()
    claims = load_claims()
    for kind in ("level", "ratio", "direction", "tolerance"):
        assert claims.rules[kind] in md
    rows = {r["id"]: r for r in read_rows(outputs["csv"])}
    gm, low, high = log_interval(ratios)
    ratio = rows["glass_variance_ratio"]
    assert (ratio["ours"], ratio["ours_low"], ratio["ours_high"]) == pytest.approx((gm, low, high))
    assert ratio["verdict"] == UNTESTABLE
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["claims_file"]["sha256"] == digest
    assert [c["id"] for c in summary["claims"]] == [c["id"] for c in claims.claims]
