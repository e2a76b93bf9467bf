"""Job ``mitigations_table`` of ``workflow/rules/mitigations.smk``: the mitigation table,
its headline table and the trade-off figure, from every mitigation's per-scene files."""

from __future__ import annotations

from .common import log


def mitigations_table_job(
    runs: list[dict],
    outputs: dict,
    *,
    figure=None,
    nulls=None,
    calibration=(),
    headline=None,
) -> list[dict]:
    """``results/tables/mitigations.*`` and the trade-off figure from every mitigation's
    per-scene files (:func:`stereovar.statistics.mitigations.mitigation_table`).

    ``runs`` holds per mitigation ``mitigation``, ``kind``, ``description``, ``spp``, the
    ``calibration_transform`` whose matched null applies, and the paths ``correlation``,
    ``intervention`` and ``scene_rows`` (lists of CSVs); ``nulls`` is the calibration's
    matched-null table (``results/tables/calibration_nulls.csv``) and ``calibration`` every
    scene's calibration rows (their ``renders`` rows: what each transform ships);
    ``headline`` the paths of the headline table
    (:func:`stereovar.statistics.mitigations.headline_table`).
    """
    from ..io.tables import read_rows, write_tables
    from ..statistics.mitigations import MITIGATION_COLUMNS, mitigation_table

    loaded = []
    for run in runs:
        entry = {k: run[k] for k in ("mitigation", "kind", "description", "spp")}
        entry.update(
            {k: run[k] for k in ("render_spp", "aux_spp", "calibration_transform") if k in run}
        )
        for key in ("correlation", "intervention", "scene_rows"):
            entry[key] = [row for path in run.get(key, []) for row in read_rows(path)]
        loaded.append(entry)
    shipped = [
        r for path in calibration for r in read_rows(path) if r["kind"] == "renders"
    ]
    rows = mitigation_table(loaded, read_rows(nulls) if nulls else None, shipped=shipped)
    write_tables(
        rows,
        MITIGATION_COLUMNS,
        outputs,
        caption=(
            "Mitigations: the cue (rho and the intensity-controlled partial rho, with the null "
            "shift and simulated-sensor controls), its Monte Carlo-specific part (partial rho "
            "minus the matched null through the same transform) and verdict, Table 3 (C_sigma "
            "WTA lift over chance, "
            "C_eps shuffle effect), the cross-view residual correlation at the ground-truth "
            "alignment and at zero disparity, and the image quality against a converged "
            "reference; 95% intervals"
        ),
    )
    if headline:
        from ..statistics.mitigations import HEADLINE_COLUMNS, headline_table

        write_tables(
            headline_table(rows),
            HEADLINE_COLUMNS,
            headline,
            caption=(
                "Mitigations, all pixels: the Monte Carlo-specific rho (intensity-controlled "
                "rho minus its matched null through the same transform) with its 95% "
                "interval, that null, the same on what seed-mean transforms ship, the C_sigma "
                "lift over chance, PSNR against a raw render at the same samples per image, "
                "and the verdict (removed: inside the calibration's equivalence margin). "
                "The full table: mitigations.csv"
            ),
        )
    for row in rows:
        log.info(
            "%-15s %-9s partial %.3f, null %.3f, Monte Carlo-specific %.3f [%.3f, %.3f] %s, "
            "residual zero-disparity %.3f [%.3f, %.3f], PSNR %.2f dB [%.2f, %.2f]",
            row["mitigation"],
            row["region"],
            row["partial"],
            row["null_partial"],
            row["mc_specific"],
            row["mc_specific_low"],
            row["mc_specific_high"],
            row["mc_cue"],
            row["residual_rho_zero"],
            row["residual_rho_zero_low"],
            row["residual_rho_zero_high"],
            row["psnr"],
            row["psnr_low"],
            row["psnr_high"],
        )
    if figure is not None:
        from ..figures.mitigations import tradeoff_figure
        from .common import save_figure

        save_figure(tradeoff_figure(rows), figure)
    return rows
