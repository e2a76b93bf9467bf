"""Jobs of ``workflow/rules/tables.smk``: Table 1 (cross-scene) and Table 2 (SPP sweep)."""

from __future__ import annotations

from .common import log, run_of


def cross_scene_job(correlations, outputs: dict, *, spp) -> list[dict]:
    """Table 1: rho across scenes per region at the main SPP, with the other statistics'
    means (``mean_rho_no_warp``, ...)."""
    from ..io.tables import read_rows, write_tables
    from ..statistics.summary import cross_scene_columns, cross_scene_table

    rows = [r for path in correlations for r in read_rows(path)]
    table = cross_scene_table(rows, spp=int(spp))
    write_tables(
        table,
        cross_scene_columns(),
        outputs,
        caption=f"Cross-scene correlation at SPP={spp} (Table 1)",
        constants=run_of(rows),
    )
    return table


def spp_sweep_job(correlations, variances, warped, outputs: dict, fit_outputs: dict) -> dict:
    """Table 2: mean left variance by region and rho by region at each SPP, plus the
    log-log slope of mean variance against SPP."""
    from ..io.store import load_store
    from ..io.tables import read_rows, write_tables
    from ..statistics.regions import REGIONS
    from ..statistics.summary import (
        SPP_SWEEP_COLUMNS,
        mean_variance_by_region,
        spp_sweep_table,
        sweep_entry,
    )

    entries, every = [], []
    for csv_path, var_path, warp_path in zip(correlations, variances, warped, strict=True):
        v = load_store(var_path, "variance store", ["variance"])
        w = load_store(warp_path, "warped store", [f"region_{k}" for k in REGIONS])
        masks = {k: w[f"region_{k}"].values for k in REGIONS}
        means = mean_variance_by_region(v["variance"].sel(view="left").values, masks)
        rows = read_rows(csv_path)
        every += rows
        entries.append(sweep_entry(int(v.attrs["spp"]), rows, means))
    rows, fit = spp_sweep_table(entries)
    run = run_of(every)
    write_tables(rows, SPP_SWEEP_COLUMNS, outputs, caption="SPP sweep (Table 2)", constants=run)
    fit_rows = [{"region": k, **f} for k, f in fit.items()]
    write_tables(
        fit_rows,
        ["region", "slope", "intercept", "r2", "n_points", "reason"],
        fit_outputs,
        caption="Log-log slope of mean variance against SPP",
        constants=run,
    )
    for row in fit_rows:
        log.info("log-log slope of mean variance vs SPP, %s: %.4f", row["region"], row["slope"])
    return fit


def cross_renderer_job(correlations: dict, outputs: dict, *, spp) -> list[dict]:
    """The cross-renderer table: per scene and their mean, each renderer's rho with its
    bootstrap interval, the robust statistics, the intensity-controlled rho, the no-warp
    control and the sensor baseline
    (:func:`stereovar.statistics.cross_renderer.cross_renderer_table`)."""
    from ..io.tables import read_rows, write_tables
    from ..statistics.cross_renderer import cross_renderer_columns, cross_renderer_table

    rows = {r: [row for p in paths for row in read_rows(p)] for r, paths in correlations.items()}
    table = cross_renderer_table(rows, spp=int(spp))
    estimators = sorted({row.get("estimator", "") for rs in rows.values() for row in rs})
    write_tables(
        table,
        cross_renderer_columns(list(rows)),
        outputs,
        caption=(
            f"Cross-renderer comparison at SPP={spp} ({', '.join(rows)}; estimator "
            f"{', '.join(estimators)}): rho with 95% block-bootstrap intervals per scene, the "
            "mean over scenes with its interval, and the controls"
        ),
    )
    for r in rows:
        mean = [t for t in table if t["scene"] == "mean" and t["method"] == "warp"]
        for t in mean:
            log.info(
                "%s, %s: mean rho %.4f [%.4f, %.4f]",
                r,
                t["region"],
                t[f"rho_{r}"],
                t[f"boot_low_{r}"],
                t[f"boot_high_{r}"],
            )
    return table
