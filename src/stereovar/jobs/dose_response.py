"""Jobs of the dose-response (``workflow/rules/mitigations.smk``): one scene's rows and the
table."""

from __future__ import annotations

from .common import log


def dose_response_scene_job(
    variance,
    ground_truth,
    out,
    *,
    renders,
    transforms,
    cameras,
    multiples,
    replicates,
    analysis=None,
    controls=None,
    seed: int = 0,
) -> list[dict]:
    """One scene's dose-response rows (:func:`stereovar.calibration.dose_response.dose_rows`
    for each transform) to one CSV.

    Parameters
    ----------
    variance, ground_truth : path
        The scene's seeds variance store at the run's SPP and its ground truth.
    renders : dict
        Budget multiple to each view's render stores at that multiple of the SPP (1: the
        run's renders; K: the ``spp_xK`` renders).
    cameras : list of dict
        ``gain`` and ``read_noise`` of each camera.
    """
    import dataclasses

    from ..calibration.dose_response import DOSE_COLUMNS, dose_rows
    from ..calibration.synthesis import channel_correlation
    from ..io.tables import write_tables
    from .calibration import _sorted_stack, scene_frames
    from .settings import analysis_settings

    settings, _ = analysis_settings(analysis or {}, controls or {})
    scene = scene_frames(variance, ground_truth)
    stacks = {int(m): {view: _sorted_stack(paths) for view, paths in views.items()}
              for m, views in renders.items()}
    if 1 in stacks:  # the synthetic frames' channels share their noise as the renders' do
        scene = dataclasses.replace(scene, channel_correlation=channel_correlation(
            stacks[1]["left"], scene.ground_truth["left"]["valid"]))
    rows = []
    name = scene.label.split("|")[0]
    for transform in transforms:
        for row in dose_rows(scene, transform=transform, cameras=cameras, settings=settings,
                             multiples=[int(m) for m in multiples],
                             replicates=int(replicates), renders=stacks, seed=int(seed)):
            rows.append({"scene": name, **row})
    write_tables(rows, DOSE_COLUMNS, {"csv": out})
    log.info("%s: %d dose-response rows (%s; cameras of gain %s; multiples %s)", name,
             len(rows), ", ".join(transforms), ", ".join(f"{c['gain']:g}" for c in cameras),
             ", ".join(map(str, multiples)))
    return rows


def dose_response_table_job(rows, outputs: dict, *, nulls=None, spp: int) -> list[dict]:
    """``results/tables/dose_response.*`` from every scene's rows
    (:func:`stereovar.statistics.dose_response.dose_table`), the budget that removes the cue
    in the caption (:func:`~stereovar.statistics.dose_response.dose_findings`)."""
    from ..io.tables import read_rows, write_tables
    from ..statistics.dose_response import (
        COMPACT_COLUMNS,
        DOSE_TABLE_COLUMNS,
        compact_table,
        dose_findings,
        dose_table,
    )

    loaded = [r for path in rows for r in read_rows(path)]
    table = dose_table(loaded, read_rows(nulls) if nulls else None, spp=int(spp))
    write_tables(table, DOSE_TABLE_COLUMNS, {"csv": outputs["csv"]})
    findings = dose_findings(table)
    write_tables(
        compact_table(table),
        COMPACT_COLUMNS,
        {k: v for k, v in outputs.items() if k != "csv"},
        caption=(
            "What a seed-mean mitigation ships, over the samples behind one shipped image and "
            "the camera it adds: the Monte Carlo-specific rho (intensity-controlled rho minus "
            "its matched null at the same budget and camera) predicted from the renders' own "
            "variance field under the 1/SPP law, and measured on the renders where the run "
            "has them (spp_xK), 95% intervals, scenes combined; render time as a multiple of "
            "one render at the run's SPP; PSNR from the shipped image's variance. "
            + " ".join(findings)
            + " Every column: dose_response.csv"
        ),
    )
    for line in findings:
        log.info("%s", line)
    return table
