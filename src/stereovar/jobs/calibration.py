"""Jobs of ``workflow/rules/calibration.smk``: one scene's replicates, then the table."""

from __future__ import annotations

from .common import log

DEFAULTS = {
    "replicates": 16,
    "denoised_replicates": 2,
    "strengths": [0.0625, 0.125, 0.25, 1.0, 2.0],
    "pipelines": [
        "shading", "gain_map", "srgb8_0.2", "srgb8_0.4", "srgb8_1", "white_balance",
        "colour_matrix", "power_law", "correlated",
    ],
    "pipeline_replicates": 5,
    "seed": 0,
}
"""The ``calibration`` config section's defaults (``config.schema.yaml`` states them)."""


def scene_frames(variance, ground_truth, aux=None):
    """:class:`~stereovar.calibration.replicates.SceneFrames` of one scene: its seeds
    variance store (the variance contract) and ground truth, and each view's auxiliary-pass
    store when the run's denoiser reads them. Renders an audit imported from integers say so
    in the store's attrs (``bit_depth`` 8 or 16, ``transfer``, ``full_scale``:
    :data:`~stereovar.io.contracts.RENDER_PROVENANCE`); their ``encoding`` is then set, and
    the matched null passes through it. Float renders (the project's own, EXR imports) have
    none."""
    import numpy as np

    from ..calibration.scene_frames import SceneFrames
    from ..io.store import load_store

    v = load_store(variance, "variance store", ["mean", "variance", "finite"])
    gt = load_store(ground_truth, "ground-truth store", ["disparity", "valid", "glass"])
    views = ("left", "right")
    mean = {k: v["mean"].sel(view=k).transpose("y", "x", "channel").values for k in views}
    fields = {
        k: np.where(
            v["finite"].sel(view=k).transpose("y", "x").values,
            v["variance"].sel(view=k).transpose("y", "x").values,
            np.nan,
        )
        for k in views
    }
    truth = {
        k: {
            "disparity": gt["disparity"].sel(view=k).transpose("y", "x").values,
            "valid": gt["valid"].sel(view=k).transpose("y", "x").values.astype(bool),
        }
        for k in views
    }
    passes = None
    if aux:
        passes = {}
        for k, path in aux.items():
            a = load_store(path, "auxiliary-pass store", ["albedo", "normal"])
            passes[k] = {
                name: a[name].transpose("y", "x", "channel").values.astype(np.float32)
                for name in ("albedo", "normal")
            }
    mean = {k: np.where(np.isfinite(m), m, 0.0) for k, m in mean.items()}
    return SceneFrames(
        mean=mean,
        variance=fields,
        ground_truth=truth,
        glass=gt["glass"].sel(view="left").transpose("y", "x").values.astype(bool),
        sign=int(gt.attrs["disparity_sign"]),
        # the frames per view: N seeds, or the samples the moments estimator drew
        n_seeds=int(v.attrs.get("n_draws", v.attrs["n_seeds"])),
        label=f"{v.attrs['scene']}|spp{int(v.attrs['spp'])}",
        aux=passes,
        encoding=stored_encoding(v.attrs),
    )


def stored_encoding(attrs) -> dict | None:
    """The integer encoding a store's renders were read from
    (:func:`~stereovar.calibration.pipelines.integer_roundtrip`'s ``bits``, ``transfer`` and
    ``scale``) when its attrs say ``bit_depth`` is 8 or 16; None otherwise."""
    bits = int(attrs.get("bit_depth") or 0)
    if bits not in (8, 16):
        return None
    return {"bits": bits, "transfer": str(attrs["transfer"]), "scale": float(attrs["full_scale"])}


def calibration_scene_job(
    variance,
    ground_truth,
    out,
    *,
    transforms,
    options=None,
    aux=None,
    renders=None,
    calibration=None,
    analysis=None,
    controls=None,
    intervention=None,
    outputs=None,
    output_renders=None,
) -> list[dict]:
    """One scene's calibration replicates
    (:func:`stereovar.calibration.replicates.scene_calibration`) to one CSV, and with
    ``renders`` (each view's render stores) what every transform that reads the seed mean
    ships, measured on the renders themselves
    (:func:`stereovar.calibration.renders.renders_shipped_rows`). ``intervention`` (its
    config section) sets the variance-matching cost's window and disparities as the
    intervention scans the renders. ``outputs`` (chain label to the writer a generator's
    renders pass through) with ``output_renders`` (each view's render stores of that
    generator) adds what the generator ships, measured on its renders
    (:func:`stereovar.calibration.renders.renders_output_rows`); each label must be one of
    ``transforms``, so that its matched null is drawn through the same chain."""
    import dataclasses

    from ..calibration.renders import renders_output_rows, renders_shipped_rows
    from ..calibration.replicates import CALIBRATION_COLUMNS, scene_calibration
    from ..io.tables import write_tables
    from ..transforms import transform_chain
    from .settings import analysis_settings

    settings, camera = analysis_settings(analysis, controls)
    cal = {**DEFAULTS, **dict(calibration or {})}
    scene = scene_frames(variance, ground_truth, aux)
    scene = dataclasses.replace(matching_scan(scene, intervention), sensor=camera)
    stacks = {}
    if renders:
        from ..calibration.synthesis import channel_correlation

        for view, paths in renders.items():
            stacks[view] = _sorted_stack(paths)
        # the renders' channels share their noise: the synthetic frames' do as much
        scene = dataclasses.replace(scene, channel_correlation=channel_correlation(
            stacks["left"], scene.ground_truth["left"]["valid"]))
    expensive = frozenset(
        t for t in transforms if t != "none" and any(x.expensive for x in transform_chain(t))
    )
    outputs = dict(outputs or {})
    unmatched = sorted(set(outputs) - set(transforms))
    if unmatched:
        raise ValueError(f"outputs {unmatched} have no matched null among {list(transforms)}")
    rows, info = scene_calibration(
        scene,
        transforms=list(transforms),
        settings=settings,
        replicates=int(cal["replicates"]),
        strength_factors=[float(s) for s in cal["strengths"]],
        expensive_replicates=int(cal["denoised_replicates"]),
        expensive=expensive,
        options=options,
        seed=int(cal["seed"]),
        pipelines=list(cal["pipelines"]),
        pipeline_replicates=int(cal["pipeline_replicates"]),
    )
    if stacks:
        rows += renders_shipped_rows(
            stacks, scene, transforms=transforms, settings=settings, options=options,
            seed=int(cal["seed"]),
        )
    if outputs and output_renders:
        rows += renders_output_rows(
            {view: _sorted_stack(paths) for view, paths in output_renders.items()}, scene,
            outputs=outputs, settings=settings, seed=int(cal["seed"]),
        )
    name = scene.label.split("|")[0]
    for row in rows:
        row["scene"] = name
    log.info(
        "%s: camera law a %.4g b %.4g; the renders' strength (sd of ln sigma^2 beyond "
        "intensity and estimation noise) %.3f; channels correlated %.2f; %d replicates (%d "
        "through %s); %d of each of %d pipeline nulls",
        name,
        *info["camera_law"],
        info["render_strength"],
        scene.channel_correlation,
        info["replicates"],
        info["expensive_replicates"],
        ", ".join(sorted(expensive)) or "no denoiser",
        info["pipeline_replicates"],
        len(cal["pipelines"]),
    )
    write_tables(rows, CALIBRATION_COLUMNS, {"csv": out})
    return rows


def _sorted_stack(paths):
    """One view's renders (N, H, W, C) from its render stores, in seed order."""
    import numpy as np

    from .common import view_stack

    stack, seeds, _, _ = view_stack(paths)
    return stack[np.argsort(seeds, kind="stable")]


def matching_scan(scene, intervention=None):
    """``scene`` with the intervention's window and largest disparity (its
    ``max_disparity``, or the largest ground truth plus ``disparity_margin``)."""
    import dataclasses

    from ..intervention.lift import DISPARITY_MARGIN, max_disparity_of

    settings = dict(intervention or {})
    largest = settings.get("max_disparity")
    if largest is None:
        gt = scene.ground_truth["left"]
        largest = max_disparity_of(gt["disparity"], gt["valid"],
                                   settings.get("disparity_margin", DISPARITY_MARGIN))
    return dataclasses.replace(scene, window=int(settings.get("window", 5)),
                               max_disparity=int(largest))


def calibration_table_job(rows, outputs: dict, *, nulls, figure=None) -> list[dict]:
    """``results/tables/calibration.csv`` (every check), ``calibration.md`` (one row per
    transform and statistic, :func:`stereovar.calibration.compact.compact_table`), the
    matched nulls and the figure from every scene's replicates
    (:func:`stereovar.calibration.summary.calibration_table`, and the claims table's level
    rule decided on them, :func:`stereovar.calibration.claims.claim_checks`)."""
    from ..calibration.claims import claim_checks
    from ..calibration.compact import COMPACT_COLUMNS, compact_table
    from ..calibration.sentences import headline
    from ..calibration.summary import CALIBRATION_TABLE_COLUMNS, NULL_COLUMNS, calibration_table
    from ..io.tables import read_rows, write_tables

    replicates = [r for path in rows for r in read_rows(path)]
    table, null_rows = calibration_table(replicates)
    table += claim_checks([r for r in replicates if r["region"] == "all"])
    sentence = headline(table)
    write_tables(table, CALIBRATION_TABLE_COLUMNS, {"csv": outputs["csv"]})
    write_tables(
        compact_table(table),
        COMPACT_COLUMNS,
        {k: v for k, v in outputs.items() if k != "csv"},
        caption=(
            f"{sentence} Per transform and statistic, the scenes combined: false-positive "
            "rates on the matched nulls (level 5%), the smallest planted strength detected "
            "with 80% power and its Monte Carlo-specific rho (the equivalence margin), and "
            "the lowest coverage of the 95% intervals over the designs (target 95 +/- 2%); "
            "95% Wilson intervals. Every check, scope and design: calibration.csv"
        ),
    )
    write_tables(null_rows, NULL_COLUMNS, {"csv": nulls})
    if figure is not None:
        from ..figures.calibration import calibration_figure
        from .common import save_figure

        save_figure(calibration_figure(table), figure)
    log.info("%s", sentence)
    return table
