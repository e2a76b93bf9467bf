"""Job of ``workflow/rules/generators.smk``: the generator table and its figure."""

from __future__ import annotations

from .common import log


def profile_matched_transform(cycles: dict) -> str:
    """The calibration transform of a profile's matched null: ``denoise`` (OIDN with albedo
    and normal, :mod:`stereovar.transforms`) when its Cycles denoiser runs, else ``none``."""
    return "denoise" if (cycles or {}).get("denoise") else "none"


def profile_output_chain(name: str, cycles: dict) -> str | None:
    """The chain a profile's shipped matched null passes through: its matched transform
    (:func:`profile_matched_transform`), then the writer it ships through
    (:data:`stereovar.generators.OUTPUTS`); None for a profile that ships floats.

    Examples
    --------
    >>> profile_output_chain("kubric", {"denoise": True})
    'denoise+png8_filmic'
    >>> profile_output_chain("infinigen", {"denoise": False})
    'png8_agx'
    >>> profile_output_chain("paper", {}) is None
    True
    """
    from ..generators import OUTPUTS

    ship = OUTPUTS.get(name)
    if ship is None:
        return None
    matched = profile_matched_transform(cycles)
    return ship if matched == "none" else f"{matched}+{ship}"


def generators_table_job(
    runs: list[dict], outputs: dict, *, figure=None, calibration=None
) -> list[dict]:
    """``results/tables/generators.*``, ``results/figures/generators.png`` and
    ``results/tables/generators_calibration.csv``.

    ``runs`` holds per profile, in table order: ``profile``, ``spp``, ``generator_spp``,
    ``scale``, ``cycles`` (the profile as rendered, :class:`stereovar.generators.
    GeneratorProfile`), ``calibration_transform`` and the paths ``correlation``,
    ``scene_rows`` (its scenes' correlation and mitigation rows) and ``calibration`` (its
    scenes' calibration replicates, matched to the profile). Each profile is measured
    against its own matched nulls (:func:`stereovar.calibration.summary.calibration_table`)
    by :func:`stereovar.statistics.mitigations.mitigation_table`; the CSV keeps every
    column, the other formats each number beside its interval
    (:func:`stereovar.statistics.generators.compact_table`), their caption the upper bound
    of each verdict's false-positive rate on its matched nulls. ``calibration`` (a path)
    keeps each profile's calibration table (a ``profile`` column, then
    :data:`~stereovar.calibration.summary.CALIBRATION_TABLE_COLUMNS`).
    """
    from ..calibration.rates import LEVEL, NOT_SHOWN, meets_level, replicates_to_show
    from ..calibration.sentences import false_positive_text, worst_false_positive
    from ..calibration.summary import CALIBRATION_TABLE_COLUMNS, calibration_table
    from ..generators import GeneratorProfile
    from ..io.tables import read_rows, write_tables
    from ..statistics.generators import (
        COMPACT_COLUMNS,
        GENERATOR_COLUMNS,
        compact_table,
        generator_rows,
        shipped_columns,
    )
    from ..statistics.mitigations import mitigation_table

    rows = []
    checks = []
    bounds = []
    for run in runs:
        profile = GeneratorProfile(
            run["profile"], int(run["spp"]), dict(run["cycles"]), float(run["scale"])
        )
        replicates = [r for path in run["calibration"] for r in read_rows(path)]
        table, nulls = calibration_table(replicates)
        checks += [{"profile": profile.name, **r} for r in table]
        # the verdict's rule on the scenes combined, through the profile's matched transform
        worst = worst_false_positive(
            table, scope="combined", transform=run["calibration_transform"], method="partial"
        )
        if worst is not None:
            bounds.append((profile.name, worst))
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
        shipped = shipped_columns(replicates, nulls, run.get("output_transform"))
        rows += [
            {**r, **(shipped if r["region"] == "all" else {"output": shipped["output"]})}
            for r in generator_rows(
                profile,
                measured,
                generator_spp=int(run["generator_spp"]),
                matched=run["calibration_transform"],
            )
        ]
    write_tables(rows, GENERATOR_COLUMNS, {"csv": outputs["csv"]})
    if calibration is not None:
        write_tables(checks, ["profile", *CALIBRATION_TABLE_COLUMNS], {"csv": calibration})
    false_positives = "The verdict's false positives on each profile's matched nulls are not known."
    if bounds:
        false_positives = (
            "The verdict's rule (the Monte Carlo-specific rho's interval above 0) calls a cue "
            "on each profile's cue-free matched nulls, scenes combined, in "
            + ", ".join(f"{name} {false_positive_text(r)}" for name, r in bounds)
            + " (upper end of the 95% Wilson interval, worst matched null)"
        )
        if any(meets_level(r["low"], r["high"]) == NOT_SHOWN for _, r in bounds):
            false_positives += (
                f"; {NOT_SHOWN}: too few replicates to show the {100 * LEVEL:g}% level, "
                f"which {replicates_to_show()} null replicates with no false positive would"
            )
        false_positives += "."
    write_tables(
        compact_table(rows),
        COMPACT_COLUMNS,
        {k: v for k, v in outputs.items() if k != "csv"},
        caption=(
            "Generator profiles, all pixels: each generator's Cycles defaults rendered on "
            "these scenes (SPP scaled to the budget where it is above it). The Monte "
            "Carlo-specific rho is the intensity-controlled rho minus the same statistic on "
            "the profile's matched null (its value beside it), with its 95% interval and "
            "verdict. As shipped: the same on the generator's own output (its renders "
            "through Blender's view transform and PNG, read back as an audit reads them), "
            "against a null drawn through the same denoiser and PNG; undefined where the "
            "codes fix the variance at 90% of the pixels or more. The residual coupling is "
            "the correlation of the views' standardised "
            "residuals at zero disparity (about 0 for independent seeds); PSNR of one render "
            f"against the converged reference. {false_positives} Every column and region: "
            "generators.csv; every calibration check: generators_calibration.csv"
        ),
    )
    for row in rows:
        if row["region"] != "all":
            continue
        log.info(
            "%-12s spp %d (x%.4g) adaptive %s, denoiser %s, seeds %s: Monte Carlo-specific "
            "%.3f [%.3f, %.3f] (null %.3f) %s; as shipped (%s) %.3f [%.3f, %.3f] (null "
            "%.3f) %s, codes fix %.0f%% of pixels; residual coupling %.3f [%.3f, %.3f], "
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
            row["output"],
            row["shipped_mc_specific"],
            row["shipped_mc_specific_low"],
            row["shipped_mc_specific_high"],
            row["shipped_null_partial"],
            row["shipped_mc_cue"],
            100 * row["quantised_share"],
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
