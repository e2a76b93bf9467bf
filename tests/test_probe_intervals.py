"""The probe table's intervals hold their level; its rows, the verdict and the figure.

The coverage simulation draws tile tables with known truth: a main network and its cue-blind
twin, J training seeds each, K test tiles; per-seed random effects (shared by a network's
inputs, and per input), per-tile heterogeneity shared by every seed (per tile, and per tile
and term), binomial hits per seed and tile (normal approximation). The true difference in
differences is ``DID``.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.stats import t as student_t

from stereovar.probe.metrics import (
    CONTROL,
    MAIN,
    TILE_COLUMNS,
    TWIN,
    detectable,
    probe_rows,
    ratio_contrast,
)
from stereovar.probe.scoring import SUMS
from stereovar.probe.verdict import mitigation_status, probe_verdict

DID = 0.01
WEIGHTS = np.array([1.0, -1.0, -1.0, 1.0])  # main normal, main shuffled, twin normal, twin shuffled

REGIMES = {
    # (SD of the per-seed per-input effect, SD of the per-tile per-term effect)
    "seeds": (0.010, 0.005),
    "tiles": (0.002, 0.030),
    "mixed": (0.006, 0.015),
    "pixels": (0.0, 0.0),  # only each network's binomial errors
}


def simulate(rng, trials, seeds, tiles, *, seed_sd, tile_sd, did=DID):
    """Per-tile hits and pixel counts, shape (trials, seeds, 4, tiles), of the four terms of
    :data:`WEIGHTS`; the expected pooled accuracies differ in differences by ``did``."""
    base = np.array([0.86, 0.78 - did, 0.85, 0.77])
    arm = np.array([0, 0, 1, 1])
    seed_effect = rng.normal(0, 0.02, (trials, seeds, 2))[:, :, arm]
    seed_effect = seed_effect + rng.normal(0, seed_sd, (trials, seeds, 4))
    tile_effect = rng.normal(0, 0.03, (trials, 1, 1, tiles))
    tile_effect = tile_effect + rng.normal(0, tile_sd, (trials, 1, 4, tiles))
    p = np.clip(base[:, None] + seed_effect[..., None] + tile_effect, 0.0, 1.0)
    n = np.broadcast_to(rng.integers(60, 257, (trials, 1, 1, tiles)), p.shape).astype(float)
    # binomial hits by their normal approximation (n p (1 - p) > 5 here), 10x faster
    hits = np.round(n * p + np.sqrt(n * p * (1 - p)) * rng.standard_normal(p.shape))
    return np.clip(hits, 0.0, n), n


@pytest.mark.parametrize("seeds", [3, 10])
@pytest.mark.parametrize("regime", list(REGIMES))
def test_the_did_interval_covers_the_truth_at_its_level(seeds, regime):
    trials = 2000  # Monte Carlo SE of a 95 % coverage: sqrt(0.95 * 0.05 / 2000) = 0.49 %
    seed_sd, tile_sd = REGIMES[regime]
    rng = np.random.default_rng([seeds, len(regime)])
    hits, n = simulate(rng, trials, seeds, 100, seed_sd=seed_sd, tile_sd=tile_sd)
    r = ratio_contrast(hits, n, WEIGHTS)
    coverage = np.mean((r["low"] <= DID) & (DID <= r["high"]))
    assert abs(coverage - 0.95) < 0.02, coverage
    # the standard error matches the spread of the estimate across trials
    assert np.sqrt(np.mean(r["se"] ** 2)) == pytest.approx(np.std(r["value"]), rel=0.1)


def test_the_tile_variance_matches_a_brute_force_tile_bootstrap():
    rng = np.random.default_rng(7)
    hits, n = simulate(rng, 1, 1, 60, seed_sd=0.0, tile_sd=0.05)
    hits, n = hits[0], n[0]  # (1, 4, K): one seed, so the interval is the tiles' alone
    r = ratio_contrast(hits, n, WEIGHTS)
    reps = []
    for _ in range(3000):
        k = rng.integers(0, 60, 60)
        acc = hits[0][:, k].sum(axis=1) / n[0][:, k].sum(axis=1)
        reps.append(acc @ WEIGHTS)
    # SE of a variance from 3000 replicates: sqrt(2 / 3000) = 2.6 %; linearisation ~1/K
    assert float(r["se"]) ** 2 == pytest.approx(np.var(reps), rel=0.12)
    assert float(r["df"]) == 59


def test_seed_only_spread_gives_the_plain_t_interval():
    # every tile of a seed has the same rates: no tile variance, the t-interval over seeds
    per_seed = np.array([0.02, 0.05, 0.03, 0.00])
    hits = np.empty((4, 4, 5))
    for j, d in enumerate(per_seed):
        rates = np.array([0.8, 0.7 - d, 0.8, 0.7])
        hits[j] = np.round(rates * 100)[:, None]
    r = ratio_contrast(hits, np.full_like(hits, 100.0), WEIGHTS)
    half = student_t.ppf(0.975, 3) * per_seed.std(ddof=1) / 2
    assert float(r["value"]) == pytest.approx(per_seed.mean(), abs=1e-12)
    assert float(r["high"] - r["value"]) == pytest.approx(half, rel=1e-9)
    assert float(r["df"]) == pytest.approx(3.0)


def test_the_smallest_detectable_did_has_its_power():
    # a true DiD equal to the MDE is detected (low > 0) in 80 % of normal draws, known SE
    se, df = 0.01, 1e6
    mde = float(detectable(se, df))
    draws = np.random.default_rng(0).normal(mde, se, 20000)
    power = np.mean(draws - 1.959964 * se > 0)
    assert power == pytest.approx(0.80, abs=0.01)


# --- the rows ---------------------------------------------------------------------------------

INPUTS = ("normal", "shuffled", "conflict")


def tile_table(rng, *, conditions=("none", CONTROL, "planted_x2"), seeds=(0, 1, 2),
               architectures=("mccnn", "costvolume"), tiles=8):
    """A synthetic tile table: each tested condition scored by its main networks, its twins
    (not ``sensor_only``) and the ``sensor_only`` main networks, seeds 0..J-1 of each."""
    rows = []
    for arch in architectures:
        for tested in conditions:
            nets = [(tested, MAIN)] + ([(tested, TWIN), (CONTROL, MAIN)] if tested != CONTROL
                                       else [])
            for scene in ("a", "b"):
                for tile in range(tiles):
                    n = int(rng.integers(30, 120))
                    for network, variant in nets:
                        for seed in seeds:
                            for t in INPUTS:
                                hits = int(rng.binomial(n, rng.uniform(0.5, 0.95)))
                                sums = {
                                    "n": n,
                                    "hits": hits,
                                    "abs_error": float(rng.uniform(0.2, 3.0) * n),
                                    "pulled": int(rng.binomial(n - hits, 0.3)),
                                    "zero": int(rng.binomial(n, 0.05)),
                                }
                                rows.append({
                                    "tested": tested, "architecture": arch, "network": network,
                                    "variant": variant, "train_seed": seed, "test_input": t,
                                    "region": "all", "scene": scene, "tile": 2 * tile + 1,
                                    **{s: sums[s] for s in SUMS},
                                })
    return pd.DataFrame(rows, columns=list(TILE_COLUMNS))


def brute(df, arch, tested, network, variant, test_input, column="hits"):
    """Per training seed: the pooled ``column / n`` over every tile, by loops."""
    out: dict = {}
    for r in df.itertuples(index=False):
        if (r.architecture, r.tested, r.network, r.variant, r.test_input) == (
            arch, tested, network, variant, test_input
        ):
            acc = out.setdefault(r.train_seed, [0.0, 0.0])
            acc[0] += getattr(r, column)
            acc[1] += r.n
    return {s: a / b for s, (a, b) in sorted(out.items())}


def test_rows_match_brute_force_and_pair_the_seeds():
    df = tile_table(np.random.default_rng(3))
    rows = probe_rows(df, strengths={"planted_x2": 1.1})
    assert len(rows) == 2 * 3 * len(INPUTS)
    assert [r["tested"] for r in rows[:: len(INPUTS)]][:3] == ["none", CONTROL, "planted_x2"]
    for row in rows:
        arch, tested, t = row["architecture"], row["tested"], row["test_input"]

        def acc(network, variant, test_input, column="hits", arch=arch, tested=tested):
            return brute(df, arch, tested, network, variant, test_input, column)

        main_n, main_t = acc(tested, MAIN, "normal"), acc(tested, MAIN, t)
        drop = {s: main_n[s] - main_t[s] for s in main_n}
        assert row["accuracy"] == pytest.approx(np.mean(list(main_t.values())), abs=1e-12)
        assert row["drop"] == pytest.approx(np.mean(list(drop.values())), abs=1e-12)
        assert row["zero"] == pytest.approx(
            np.mean(list(acc(tested, MAIN, t, "zero").values())), abs=1e-12
        )
        assert row["n_tiles"] == 16 and row["train_seeds"] == 3
        for name in ("accuracy", "epe", "drop", "zero"):
            assert row[f"{name}_low"] <= row[name] + 1e-12 <= row[f"{name}_high"] + 2e-12
        if tested == CONTROL:
            assert math.isnan(row["did"]) and math.isnan(row["did_sensor"])
            assert row["sensor_accuracy"] == pytest.approx(row["accuracy"], abs=1e-12)
            continue
        twin_n, twin_t = acc(tested, TWIN, "normal"), acc(tested, TWIN, t)
        did = [drop[s] - (twin_n[s] - twin_t[s]) for s in drop]
        sen_n, sen_t = acc(CONTROL, MAIN, "normal"), acc(CONTROL, MAIN, t)
        did_sensor = [drop[s] - (sen_n[s] - sen_t[s]) for s in drop]
        assert row["did"] == pytest.approx(np.mean(did), abs=1e-12)
        assert row["did_sensor"] == pytest.approx(np.mean(did_sensor), abs=1e-12)
        assert row["twin_accuracy"] == pytest.approx(np.mean(list(twin_t.values())), abs=1e-12)
        if t == "normal":
            assert row["did"] == 0 and row["did_low"] == row["did_high"] == 0
        else:
            # the seed part alone is a lower bound of the variance
            assert row["did_se"] >= np.std(did, ddof=1) / np.sqrt(3) - 1e-12
            assert row["did_low"] < row["did"] < row["did_high"]
            assert row["did_mde"] == pytest.approx(
                (student_t.ppf(0.975, row["did_df"]) + student_t.ppf(0.8, row["did_df"]))
                * row["did_se"]
            )
        if t == "conflict":
            pulled = acc(tested, MAIN, t, "pulled")
            twin_pulled = acc(tested, TWIN, t, "pulled")
            assert row["pulled_vs_twin"] == pytest.approx(
                np.mean([pulled[s] - twin_pulled[s] for s in pulled]), abs=1e-12
            )
        else:
            assert math.isnan(row["pulled"])
        if tested == "planted_x2":
            assert (row["strength_factor"], row["strength"]) == (2.0, 1.1)
        else:
            assert math.isnan(row["strength_factor"]) and math.isnan(row["strength"])


def test_rows_take_the_renders_strength_times_the_factor():
    df = tile_table(np.random.default_rng(4), conditions=("none", "planted_x0.5"),
                    architectures=("mccnn",), tiles=3)
    rows = probe_rows(df, strengths=0.4)
    planted = [r for r in rows if r["tested"] == "planted_x0.5"]
    assert [r["strength"] for r in planted] == pytest.approx([0.2] * len(INPUTS))
    by_factor = probe_rows(df, strengths={"0.5": 0.3})
    assert [r["strength"] for r in by_factor if r["tested"] == "planted_x0.5"] == [0.3] * 3


def test_rows_reject_incomplete_tables():
    df = tile_table(np.random.default_rng(5), conditions=("none",), architectures=("mccnn",),
                    tiles=3)
    with pytest.raises(ValueError, match="lacks columns"):
        probe_rows(df.drop(columns=["variant"]))
    with pytest.raises(ValueError, match="normal"):
        probe_rows(df[df["test_input"] != "normal"])
    with pytest.raises(ValueError, match="no main network"):
        probe_rows(df[(df["network"] != "none") | (df["variant"] != MAIN)])
    # without the sensor_only networks the second control is NaN, the twin DiD stays
    rows = probe_rows(df[df["network"] != CONTROL])
    assert all(math.isnan(r["did_sensor"]) for r in rows)
    assert all(math.isfinite(r["did"]) for r in rows)


# --- the verdict and the figure ---------------------------------------------------------------


def signal_table(rng, dids, *, seeds=4, tiles=30, architectures=("costvolume", "mccnn"),
                 control_twin=False):
    """A tile table whose main networks lose ``dids[condition]`` more accuracy to the shuffle
    than their twins (and than the sensor_only networks); every network on every tile
    (``control_twin``: the sensor_only networks have twins too, as ``probe.mitigations``
    trains them)."""
    rows = []
    for arch in architectures:
        for tested, did in dids.items():
            nets = [(tested, MAIN)] + ([(tested, TWIN), (CONTROL, MAIN)] if tested != CONTROL
                                       else [(CONTROL, TWIN)] if control_twin else [])
            n = rng.integers(100, 256, tiles)
            for network, variant in nets:
                extra = did if (network, variant) == (tested, MAIN) else 0.0
                for seed in range(seeds):
                    u = rng.normal(0, 0.003)
                    for t, p in (("normal", 0.88), ("shuffled", 0.80 - extra + u),
                                 ("conflict", 0.82)):
                        hits = rng.binomial(n, np.clip(p + rng.normal(0, 0.02, tiles), 0, 1))
                        for k in range(tiles):
                            rows.append({
                                "tested": tested, "architecture": arch, "network": network,
                                "variant": variant, "train_seed": seed, "test_input": t,
                                "region": "all", "scene": "s", "tile": k, "n": n[k],
                                "hits": hits[k], "abs_error": 0.5 * n[k],
                                "pulled": rng.binomial(n[k] - hits[k], 0.2),
                                "zero": rng.binomial(n[k], 0.02),
                            })
    return pd.DataFrame(rows, columns=list(TILE_COLUMNS))


DIDS = {"none": 0.0, CONTROL: 0.0, "shared_seed": 0.05, "planted_x0": 0.0,
        "planted_x1": 0.004, "planted_x2": 0.02, "planted_x4": 0.06}


@pytest.fixture(scope="module")
def signal_rows():
    return probe_rows(signal_table(np.random.default_rng(11), DIDS),
                      strengths={"planted_x1": 0.5, "planted_x2": 1.0, "planted_x4": 2.0})


def test_verdict_per_architecture_with_power_and_the_primary_on_top(signal_rows):
    v = probe_verdict(signal_rows)
    assert v["primary"] == "mccnn" and set(v["architectures"]) == {"mccnn", "costvolume"}
    none = next(r for r in signal_rows if (r["architecture"], r["tested"], r["test_input"])
                == ("mccnn", "none", "shuffled"))
    assert v["did"] == none["did"] and v["mde"] == none["did_mde"]
    assert v["uses_cue"] is False and v["not_detectable_below"] == none["did_mde"]
    assert f"not detectable below {none['did_mde']:.3f}" in v["paragraph"]
    assert f"{none['did']:+.3f}" in v["paragraph"]
    # the power curve: factors in order, the strong plants detected, the null not
    power = v["power"]
    assert [p["factor"] for p in power] == [0, 1, 2, 4]
    assert [p["detected"] for p in power][2:] == [True, True]
    assert power[0]["detected"] is False
    assert v["detected_from_factor"] in (1.0, 2.0)
    assert power[3]["strength"] == 2.0
    # a mitigation that makes it worse still uses the cue
    (shared,) = v["mitigations"]
    assert shared["condition"] == "shared_seed" and shared["status"] == "still uses"
    assert v["claim"]["answer"] == "no" and v["control"] == "cue-blind twin"


def test_mitigations_are_judged_against_none_and_a_seed_mean_one_is_not_testable():
    """probe.mitigations: each mitigation's DiD against its own twin is judged against none's
    (none relies on the cue by 0.08, the mitigations by 0). sensor_only builds every image
    from one seed mean, which the shuffle cannot reach: its row says so instead of a status;
    without its twin the control is no mitigation row."""
    dids = {"none": 0.08, CONTROL: 0.0, "denoise": 0.0}
    twinned = probe_rows(signal_table(np.random.default_rng(12), dids, seeds=6,
                                      architectures=("costvolume",), control_twin=True))
    shuffled = {r["tested"]: r for r in twinned if r["test_input"] == "shuffled"}
    assert math.isnan(shuffled[CONTROL]["did_sensor"])
    v = probe_verdict(twinned)
    assert v["uses_cue"] is True
    control, denoise = v["mitigations"]
    assert denoise["condition"] == "denoise" and denoise["did"] == shuffled["denoise"]["did"]
    assert denoise["reduced"] and denoise["difference_high"] < 0  # 0.08 less than none's
    assert denoise["status"] == mitigation_status(shuffled["denoise"], shuffled["none"],
                                                  v["mde"])["status"]
    assert control["condition"] == CONTROL and control["status"] == "not testable"
    assert not control["removes"] and "seed mean" in control["reason"]
    assert "sensor_only" in v["paragraph"] and "not testable" in v["paragraph"]
    plain = probe_rows(signal_table(np.random.default_rng(12), dids, seeds=6,
                                    architectures=("costvolume",)))
    assert [m["condition"] for m in probe_verdict(plain)["mitigations"]] == ["denoise"]


def test_a_seed_mean_mitigation_is_judged_on_what_it_ships():
    """A judged seed-mean mitigation trains as ``sensor_only_shipped`` (independent images of
    2 seeds each): its row gets the rule's status with the note, and the one-seed-mean
    condition of the same name no row. Planted: none relies by 0.08, the shipped images by
    0.08 (still uses) or by 0 (removes, or not determined where the margin is too wide)."""
    for shipped_did, expected in ((0.08, {"still uses"}),
                                  (0.0, {"removes", "not determined"})):
        dids = {"none": 0.08, CONTROL: 0.0, "sensor_only_shipped": shipped_did}
        rows = probe_rows(signal_table(np.random.default_rng(13), dids, seeds=6,
                                       architectures=("costvolume",), control_twin=True))
        shuffled = {r["tested"]: r for r in rows if r["test_input"] == "shuffled"}
        v = probe_verdict(rows)
        (row,) = v["mitigations"]  # sensor_only itself: judged through its shipped images
        assert (row["condition"], row["mitigation"]) == ("sensor_only_shipped", "sensor_only")
        assert row["did"] == shuffled["sensor_only_shipped"]["did"]
        assert row["status"] == mitigation_status(shuffled["sensor_only_shipped"],
                                                  shuffled["none"], v["mde"])["status"]
        assert row["status"] in expected and "reason" not in row
        assert "what it ships" in row["note"] and row["note"] in v["paragraph"]


def test_mitigation_status_rules():
    def row(did, se, df=1e6):
        half = 1.959964 * se
        return {"did": did, "did_low": did - half, "did_high": did + half, "did_se": se,
                "did_df": df}

    none = row(0.05, 0.01)
    # reduced (diff -0.05 +/- 1.96 * 0.0141) and equivalent (+/-1.645 * 0.01 inside 0.028)
    assert mitigation_status(row(0.0, 0.01), none, 0.028)["status"] == "removes"
    # reduced, but the 90 % interval +/-0.0164 sticks out of a 0.015 margin
    out = mitigation_status(row(0.0, 0.01), none, 0.015)
    assert out["reduced"] and not out["equivalent"] and out["status"] == "not determined"
    assert out["difference_high"] == pytest.approx(-0.05 + 1.959964 * math.sqrt(2) * 0.01,
                                                   rel=1e-5)
    # above 0 and not below none's
    assert mitigation_status(row(0.06, 0.01), none, 0.028)["status"] == "still uses"
    # neither shown
    assert mitigation_status(row(0.03, 0.02), none, 0.028)["status"] == "not determined"
    # no twin: nothing to compare
    assert mitigation_status(row(math.nan, math.nan), none, 0.028)["status"] == (
        "not determined")


def test_the_claims_row_reads_the_verdict(signal_rows):
    from stereovar.jobs.claims import probe_claim

    v = probe_verdict(signal_rows)
    claim = probe_claim(v)
    assert claim["ours"] == v["did"] and claim["verdict"] == "no"
    assert "cue-blind twin" in claim["control"]


def test_the_figure_draws_both_panels_per_architecture(signal_rows, tmp_path):
    from stereovar.figures.probe import probe_figure

    fig = probe_figure(signal_rows)
    assert len(fig.axes) == 4
    power = fig.axes[1]
    assert any("smallest detectable" in t.get_text() for t in power.get_legend().get_texts())
    fig.savefig(tmp_path / "probe.png", dpi=60)
    assert (tmp_path / "probe.png").stat().st_size > 0
