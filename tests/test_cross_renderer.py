"""The cross-renderer table against a brute-force reference on synthetic correlation rows."""

import math

import numpy as np
import pytest

from stereovar.statistics.cross_renderer import (
    METHODS,
    cross_renderer_columns,
    cross_renderer_table,
)

from .test_across import on_fisher_z

Z = 1.959963984540054


def synthetic_rows(renderer, rng, scenes=("s0", "s1", "s2"), spp=16):
    rows = []
    for scene in scenes:
        for region in ("all", "non_glass", "glass"):
            for method in (*METHODS, "null_flip"):
                rho = float(rng.uniform(-0.2, 0.9))
                half = float(rng.uniform(0.01, 0.2))
                rows.append(
                    {
                        "scene": scene,
                        "spp": spp,
                        "region": region,
                        "method": method,
                        "rho": rho,
                        "boot_low": rho - half,
                        "boot_high": rho + half,
                        "fisher_low": rho - half / 10,
                        "fisher_high": rho + half / 10,
                        "renderer": renderer,
                    }
                )
    # another SPP that the table must ignore
    rows.append({**rows[0], "spp": spp * 2, "rho": 5.0})
    return rows


def test_cross_renderer_table_against_brute_force():
    rng = np.random.default_rng(2)
    data = {"mitsuba": synthetic_rows("mitsuba", rng), "cycles": synthetic_rows("cycles", rng)}
    table = cross_renderer_table(data, spp=16)
    assert list(table[0]) == cross_renderer_columns(["mitsuba", "cycles"])
    # 3 scenes + the mean, 3 regions, the compared methods (not null_flip)
    assert len(table) == 4 * 3 * len(METHODS)
    for row in table:
        for r, rows in data.items():
            picked = [
                x
                for x in rows
                if x["spp"] == 16 and x["region"] == row["region"] and x["method"] == row["method"]
            ]
            if row["scene"] != "mean":
                (only,) = [x for x in picked if x["scene"] == row["scene"]]
                assert row[f"rho_{r}"] == only["rho"]
                assert (row[f"boot_low_{r}"], row[f"boot_high_{r}"]) == (
                    only["boot_low"],
                    only["boot_high"],
                )
                continue
            rho = np.array([x["rho"] for x in picked])
            se = np.array([(x["boot_high"] - x["boot_low"]) / (2 * Z) for x in picked])
            half = Z * math.sqrt(float((se**2).sum())) / len(picked)
            assert row[f"rho_{r}"] == pytest.approx(rho.mean(), rel=1e-12)
            # a correlation's interval: the normal one's length, placed on Fisher's z
            assert (row[f"boot_low_{r}"], row[f"boot_high_{r}"]) == pytest.approx(
                on_fisher_z(rho.mean(), half), rel=1e-9
            )
            assert row["n_scenes"] == 3
        assert row["diff_cycles_minus_mitsuba"] == pytest.approx(
            row["rho_cycles"] - row["rho_mitsuba"]
        )


def test_a_renderer_without_a_scene_shows_nan():
    rng = np.random.default_rng(3)
    data = {
        "mitsuba": synthetic_rows("mitsuba", rng),
        "cycles": synthetic_rows("cycles", rng, scenes=("s0",)),
    }
    table = cross_renderer_table(data, spp=16)
    s2 = [r for r in table if r["scene"] == "s2"]
    assert s2 and all(math.isnan(r["rho_cycles"]) for r in s2)
    assert all(math.isfinite(r["rho_mitsuba"]) for r in s2)
