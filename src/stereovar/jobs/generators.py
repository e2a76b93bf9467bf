"""Job of ``workflow/rules/generators.smk``: the generator table and its figure."""

from __future__ import annotations

from .common import log


def profile_matched_transform(cycles: dict) -> str:
    """The calibration transform of a profile's matched null: ``denoise`` (OIDN with albedo
    and normal, :mod:`stereovar.transforms`) when its Cycles denoiser runs, else ``none``."""
    return "denoise" if (cycles or {}).get("denoise") else "none"


def generators_table_job(runs: list[dict], outputs: dict, *, figure=None) -> list[dict]:
    """``results/tables/generators.*`` and ``results/figures/generators.png``.

    ``runs`` holds per profile, in table order: ``profile``, ``spp``, ``generator_spp``,
    ``scale``, ``cycles`` (the profile as rendered, :class:`stereovar.generators.
    GeneratorProfile`), ``calibration_transform`` and the paths ``correlation``,
    ``scene_rows`` (its scenes' correlation and mitigation rows) and ``calibration`` (its
    scenes' calibration replicates, matched to the profile). Each profile is measured
    against its own matched nulls (:func:`stereovar.calibration.summary.calibration_table`)
    by :func:`stereovar.statistics.mitigations.mitigation_table`; the CSV keeps every
    column, the other formats each number beside its interval
    (:func:`stereovar.statistics.generators.compact_table`).
    """
    from ..calibration.summary import calibration_table
    from ..generators import GeneratorProfile
    from ..io.tables import read_rows, write_tables
    from ..statistics.generators import (
        COMPACT_COLUMNS,
        GENERATOR_COLUMNS,
        compact_table,
        generator_rows,
    )
    from ..statistics.mitigations import mitigation_table

    rows = []
    for run in runs:
        profile = GeneratorProfile(
            run["profile"], int(run["spp"]), dict(run["cycles"]), float(run["scale"])
        )
        replicates = [r for path in run["calibration"] for r in read_rows(path)]
        _, nulls = calibration_table(replicates)
        entry = {
            "mitigation": profile.name,
            "kind": "profile",
            "description": f"Cycles under the {profile.name} profile",
            "spp": profile.spp,
            "calibration_transform": run["calibration_transform"],
            "intervention": [],
            "correlation": [r for path in run["correlation"] for r in read_rows(path)],
            "scene_rows": [r for path in run["scene_rows"] for r in read_rows(path)],
        }
        measured = mitigation_table([entry], nulls)
        rows += generator_rows(
            profile,
            measured,
            generator_spp=int(run["generator_spp"]),
            matched=run["calibration_transform"],
        )
    write_tables(rows, GENERATOR_COLUMNS, {"csv": outputs["csv"]})
    write_tables(
        compact_table(rows),
        COMPACT_COLUMNS,
        {k: v for k, v in outputs.items() if k != "csv"},
        caption=(
            "Generator profiles, all pixels: each generator's Cycles defaults rendered on "
            "these scenes (SPP scaled to the budget where it is above it). The Monte "
            "Carlo-specific rho is the intensity-controlled rho minus the same statistic on "
            "the profile's matched null (its value beside it), with its 95% interval and "
            "verdict; the residual coupling is the correlation of the views' standardised "
            "residuals at zero disparity (about 0 for independent seeds); PSNR of one render "
            "against the converged reference. Every column and region: generators.csv"
        ),
    )
    for row in rows:
        if row["region"] != "all":
            continue
        log.info(
            "%-12s spp %d (x%.4g) adaptive %s, denoiser %s, seeds %s: Monte Carlo-specific "
            "%.3f [%.3f, %.3f] (null %.3f) %s, residual coupling %.3f [%.3f, %.3f], "
            "PSNR %.1f dB",
            row["profile"],
            row["spp"],
            row["spp_scale"],
            row["adaptive"],
            row["denoiser"],
            row["seed_rule"],
            row["mc_specific"],
            row["mc_specific_low"],
            row["mc_specific_high"],
            row["null_partial"],
            row["mc_cue"],
            row["residual_rho_zero"],
            row["residual_rho_zero_low"],
            row["residual_rho_zero_high"],
            row["psnr"],
        )
    if figure is not None:
        from ..figures.generators import generators_figure
        from .common import save_figure

        save_figure(generators_figure(rows), figure)
    return rows
