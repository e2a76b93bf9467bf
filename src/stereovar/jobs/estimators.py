"""Jobs of ``workflow/rules/estimators.smk``: the moments estimator against N seeds.

For each scene, the ``moments`` field (one render per view) is compared with an Eq. 1
reference over ``validation.n_seeds`` seeds at the same SPP: how the two fields agree, and
every statistic and control of Eq. 3 computed from each, side by side.
"""

from __future__ import annotations

import math

from ..statistics.reliability import corrected_interval
from .common import log

FIELD_COLUMNS = [
    "scene",
    "view",
    "spp",
    "n_seeds_reference",
    "n_pixels",
    "mean_ratio",
    "ratio_low",
    "ratio_high",
    "spearman",
    "pearson",
    "reference_reliability_spearman",
    "reference_reliability_pearson",
    "moments_reliability_spearman",
    "moments_reliability_pearson",
]
"""Columns of ``results/{renderer}/estimators/{scene}/spp{spp}_fields.csv`` and of
``results/tables/estimator_fields.*``: per view, the moment field against the reference
(mean-level ratio moments / reference with its block-bootstrap interval, Spearman and
Pearson over the pixels where both are defined) and each estimate's split-half
reliability (Spearman-Brown)."""

ESTIMATOR_COLUMNS = [
    "scene",
    "spp",
    "region",
    "method",
    "seeds_rho",
    "seeds_low",
    "seeds_high",
    "seeds_corrected",
    "seeds_corrected_low",
    "seeds_corrected_high",
    "moments_rho",
    "moments_low",
    "moments_high",
    "moments_corrected",
    "moments_corrected_low",
    "moments_corrected_high",
    "corrected_agree",
]
"""Columns of ``results/{renderer}/estimators/{scene}/spp{spp}.csv`` and of
``results/tables/estimators.*``: each statistic's :math:`\\rho` with its block-bootstrap
interval by both estimators, the attenuation-corrected value and its interval (the
bootstrap interval divided by :math:`\\sqrt{r_L r_R}`, the reliabilities held fixed), and
whether the two corrected intervals overlap."""


def side_by_side(seeds_rows: list[dict], moments_rows: list[dict]) -> list[dict]:
    """:data:`ESTIMATOR_COLUMNS` rows from the correlation rows of each estimator
    (:func:`stereovar.statistics.rows.correlation_rows`), matched by region and method."""
    moments = {(r["region"], r["method"]): r for r in moments_rows}
    out = []
    for s in seeds_rows:
        m = moments.get((s["region"], s["method"]))
        if m is None:
            continue
        row = {"region": s["region"], "method": s["method"]}
        for name, source in (("seeds", s), ("moments", m)):
            low, high = corrected_interval(source)
            row.update(
                {
                    f"{name}_rho": source["rho"],
                    f"{name}_low": source["boot_low"],
                    f"{name}_high": source["boot_high"],
                    f"{name}_corrected": source.get("rho_corrected", math.nan),
                    f"{name}_corrected_low": low,
                    f"{name}_corrected_high": high,
                }
            )
        bounds = [row[k] for k in ("seeds_corrected_low", "seeds_corrected_high")]
        other = [row[k] for k in ("moments_corrected_low", "moments_corrected_high")]
        if all(math.isfinite(v) for v in (*bounds, *other)):
            row["corrected_agree"] = bool(bounds[0] <= other[1] and other[0] <= bounds[1])
        else:
            row["corrected_agree"] = None
        out.append(row)
    return out


def estimator_check_job(
    moments: dict,
    seeds: dict,
    ground_truth,
    outputs: dict,
    *,
    analysis=None,
    controls=None,
) -> None:
    """Compare one scene's moment field with its N-seed reference at the same SPP.

    ``moments`` and ``seeds`` map each view to its moment store and to its seed render
    stores; ``outputs`` has ``fields`` (:data:`FIELD_COLUMNS`, one row per view) and
    ``rows`` (:data:`ESTIMATOR_COLUMNS`). The reference is Eq. 1 over the seeds times
    :math:`N/(N-1)` in the field comparison, so both estimate the pixel variance without
    the population factor (:func:`stereovar.estimators.moments.pixel_variance`); every
    correlation is unaffected by that constant.
    """
    import numpy as np

    from ..estimators.moments import moment_variance_dataset
    from ..estimators.seeds import variance_dataset
    from ..io.store import load_store
    from ..io.tables import write_tables
    from ..rig import VIEWS
    from ..seeding import derive_seed
    from ..statistics.agreement import field_agreement, split_half_reliability
    from ..statistics.rows import correlation_rows
    from .correlation import align, scene_inputs
    from .settings import analysis_settings

    settings, sensor = analysis_settings(analysis, controls)
    gt = load_store(ground_truth, "ground-truth store", ["disparity", "valid", "glass"])
    estimates = {
        "moments": moment_variance_dataset(moments["left"], moments["right"]),
        "seeds": variance_dataset(seeds["left"], seeds["right"]),
    }
    m, s = estimates["moments"], estimates["seeds"]
    provenance = {}
    for path in (moments["left"][0], seeds["left"][0]):
        provenance.update(load_store(path, "render store", []).attrs)
    for ds in estimates.values():
        ds.attrs.update(scene=provenance["scene"], spp=int(provenance["spp"]))
    scene, spp = provenance["scene"], int(provenance["spp"])
    n = int(s.attrs["n_seeds"])
    fields = []
    for view in VIEWS:
        defined = (m["finite"] & s["finite"]).sel(view=view).values
        reference = s["variance"].sel(view=view).values * (n / (n - 1))
        row = {
            "scene": scene,
            "view": view,
            "spp": spp,
            "n_seeds_reference": n,
            **field_agreement(
                m["variance"].sel(view=view).values,
                reference,
                defined,
                settings=settings.bootstrap,
                seed=derive_seed(settings.bootstrap.seed, "estimators", scene, view),
            ),
        }
        for name, ds in (("reference", s), ("moments", m)):
            rel = split_half_reliability(
                ds["half_variance"].sel(view=view).transpose("half", "y", "x").values, defined
            )
            row.update({f"{name}_{k}": v for k, v in rel.items()})
        log.info(
            "%s %s: moments / %d seeds mean level %.3f [%.3f, %.3f], Spearman %.3f, "
            "Pearson %.3f; reference split-half reliability Spearman %.3f, Pearson %.3f",
            scene,
            view,
            n,
            row["mean_ratio"],
            row["ratio_low"],
            row["ratio_high"],
            row["spearman"],
            row["pearson"],
            row["reference_reliability_spearman"],
            row["reference_reliability_pearson"],
        )
        fields.append(row)
    glass = gt["glass"].sel(view="left").values
    rows = {}
    for name, ds in estimates.items():
        sigma = {v: ds["variance"].sel(view=v).values for v in VIEWS}
        rows[name] = correlation_rows(
            sigma["left"],
            sigma["right"],
            align(ds, gt),
            np.asarray(glass),
            finite_right=ds["finite"].sel(view="right").values,
            settings=settings,
            inputs=scene_inputs(ds, gt, sensor),
        )
    table = side_by_side(rows["seeds"], rows["moments"])
    for row in table:
        row.update(scene=scene, spp=spp)
        if row["region"] == "all":
            log.info(
                "%s %-10s seeds %.3f (corrected %.3f) moments %.3f (corrected %.3f) agree %s",
                scene,
                row["method"],
                row["seeds_rho"],
                row["seeds_corrected"],
                row["moments_rho"],
                row["moments_corrected"],
                row["corrected_agree"],
            )
    write_tables(fields, FIELD_COLUMNS, {"csv": outputs["fields"]})
    write_tables(table, ESTIMATOR_COLUMNS, {"csv": outputs["rows"]})


def _mean_rows(rows: list[dict], columns: list[str], keys: list[str]) -> list[dict]:
    """Per-scene rows plus, per ``keys`` group, a ``mean`` row (numeric columns averaged,
    ``corrected_agree`` the fraction of scenes that agree)."""
    import pandas as pd

    frame = pd.DataFrame(rows, columns=columns)
    if frame.empty:
        return []
    numeric = [c for c in columns if c not in ("scene", *keys) and c != "corrected_agree"]
    frame[numeric] = frame[numeric].apply(pd.to_numeric, errors="coerce")
    agg = {c: "mean" for c in numeric}
    if "corrected_agree" in frame:
        frame["corrected_agree"] = frame["corrected_agree"].map(
            {True: 1.0, False: 0.0, "True": 1.0, "False": 0.0}
        )
        agg["corrected_agree"] = "mean"
    mean = frame.groupby(keys, sort=False).agg(agg).reset_index()
    mean["scene"] = "mean"
    return pd.concat([frame, mean[columns]], ignore_index=True).to_dict("records")


def estimator_tables_job(fields, rows, outputs: dict, fields_outputs: dict, figure) -> None:
    """``results/tables/estimators.*`` and ``estimator_fields.*`` over every scene (with a
    ``mean`` row per group), and the estimator figure."""
    from ..figures.estimators import estimator_figure
    from ..io.tables import read_rows, write_tables
    from .common import save_figure

    field_rows = [r for path in fields for r in read_rows(path)]
    stat_rows = [r for path in rows for r in read_rows(path)]
    spp = field_rows[0]["spp"] if field_rows else "?"
    n = field_rows[0]["n_seeds_reference"] if field_rows else "?"
    write_tables(
        _mean_rows(field_rows, FIELD_COLUMNS, ["view"]),
        FIELD_COLUMNS,
        fields_outputs,
        caption=(
            f"The moments estimator's field (one render per view, SPP {spp}) against Eq. 1 "
            f"over N = {n} seeds at the same SPP: mean-level ratio with its 95% block-"
            "bootstrap interval, rank and Pearson correlation, and each estimate's split-half "
            "reliability"
        ),
    )
    table = _mean_rows(stat_rows, ESTIMATOR_COLUMNS, ["region", "method"])
    write_tables(
        table,
        ESTIMATOR_COLUMNS,
        outputs,
        caption=(
            f"Every statistic by both estimators at SPP {spp} (seeds: N = {n}; moments: one "
            "render per view): rho with its 95% block-bootstrap interval, the attenuation-"
            "corrected rho with that interval divided by sqrt(r_L r_R), and whether the "
            "corrected intervals overlap (mean rows: the fraction of scenes that do)"
        ),
    )
    save_figure(estimator_figure(field_rows, stat_rows), figure)
    agree = [r for r in stat_rows if str(r.get("corrected_agree")) in ("True", "False")]
    log.info(
        "corrected rho agrees within the intervals in %d of %d scene/region/statistic rows",
        sum(str(r["corrected_agree"]) == "True" for r in agree),
        len(agree),
    )
