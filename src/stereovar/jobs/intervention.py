"""Jobs of ``workflow/rules/intervention.smk``: the residual-shuffle intervention (Sec. 3.4)."""

from __future__ import annotations

from .common import log, run_of

INTERVENTION_COLUMNS = [
    "scene",
    "spp",
    "n_seeds",
    "max_disparity",
    "window",
    "block",
    "source",
    "cost",
    "metric",
    "region",
    "condition",
    "value",
    "low",
    "high",
    "chance",
    "n_pixels",
    "reason",
]
"""Columns of ``results/{renderer}/seeds/intervention/{scene}.csv``."""

MARGIN_COLUMNS = ["scene", "cost", "region", "condition", "seed", "y", "x", "margin"]
"""Columns of the GT-margin sample ``.../intervention/margins/{scene}.csv``."""

ESTIMATOR = "seeds"
"""The intervention splits each seed into mean and residual: its variance is always Eq. 1
over the seeds."""


def intervention_job(
    left,
    right,
    ground_truth,
    out,
    margins,
    *,
    window=5,
    block=16,
    seed=0,
    max_disparity=None,
    disparity_margin=4,
    margin_samples=2000,
    workers=1,
    sensor=None,
    bootstrap=None,
) -> list[dict]:
    """Table 3's metrics of one scene, normal against decorrelated (paper Sec. 3.4), and a
    sample of the per-pixel GT margins for the distribution figure.

    The ``all`` region (:math:`\\Omega`) is always scored, and with a glass mask also
    Table 3's ``non_glass`` and ``glass``; without one those two are NaN rows with the reason
    (:func:`blank_region_rows`).

    With ``sensor`` (the ``controls.sensor`` settings) the same metrics are computed again on
    N simulated Poisson-Gaussian frames per view around the seed mean
    (:class:`stereovar.controls.sensor.SensorFrames`): rows with ``source`` ``sensor``
    beside the renders' ``render`` rows, Table 3's sensor column.

    ``bootstrap`` (``analysis.bootstrap``) gives the :math:`C_\\sigma` accuracy its
    tile-bootstrap interval (``low``, ``high``; region ``all``, normal condition), which
    the audit's matching-cue rule reads."""
    import math

    from ..intervention.metrics import REGIONS, intervention_metrics
    from ..io.renders import LazyRenders, RenderStore
    from ..io.store import load_store
    from ..io.tables import write_tables

    gt = load_store(ground_truth, "ground-truth store", ["disparity", "valid", "glass"])
    gl = {k: gt[k].sel(view="left").values for k in ("disparity", "valid", "glass")}
    largest = float(gl["disparity"][gl["valid"]].max()) if gl["valid"].any() else 0.0
    if max_disparity is None:
        max_disparity = int(math.ceil(largest)) + int(disparity_margin)
    elif max_disparity < largest:
        n_lost = int((gl["valid"] & (gl["disparity"] >= max_disparity + 1)).sum())
        log.warning(
            "intervention.max_disparity = %d is below the largest ground-truth disparity %.1f"
            " px: %d valid left pixels become unscoreable; raise it or set it to null",
            max_disparity,
            largest,
            n_lost,
        )
    from ..statistics.bootstrap import BootstrapSettings

    renders_l, renders_r = LazyRenders(left), LazyRenders(right)
    no_mask = gt.attrs.get("material_mask") == "none"
    options = {
        "sign": int(gt.attrs["disparity_sign"]),
        "max_disparity": int(max_disparity),
        "window": window,
        "block": block,
        "seed": seed,
        "workers": workers,
        # `all` always (the audit's verdict reads it), Table 3's regions with a glass mask
        "regions": ("all",) if no_mask else ("all", *REGIONS),
        "bootstrap": None if bootstrap is None else BootstrapSettings(**bootstrap),
    }
    result = intervention_metrics(
        renders_l, renders_r, gl, margin_samples=margin_samples, **options
    )
    attrs = RenderStore(left[0]).attrs
    scene = attrs.get("scene", gt.attrs.get("scene"))
    for row in result.rows:
        row["source"] = "render"
    if sensor is not None:
        result.rows.extend(
            sensor_rows(renders_l, renders_r, gl, sensor, label=str(scene), **options)
        )
    if no_mask:
        result.rows.extend(blank_region_rows(result.rows))
    for row in result.rows:
        row.update(
            scene=scene,
            spp=attrs.get("spp"),
            n_seeds=len(renders_l),
            max_disparity=int(max_disparity),
            window=window,
            block=block,
        )
        log.info(
            "%-6s %-13s %-13s %-9s %-12s %.4g (chance %.4g, n=%d)%s",
            row["source"],
            row["cost"],
            row["metric"],
            row["region"],
            row["condition"],
            row["value"],
            row["chance"],
            row["n_pixels"],
            f" [{row['reason']}]" if row["reason"] else "",
        )
    if not no_mask:  # Fig. 4 shows Table 3's regions: no margin sample of `all` beside them
        result.margins[:] = [m for m in result.margins if m["region"] != "all"]
    for sample in result.margins:
        sample["scene"] = scene
    run = {"renderer": attrs.get("renderer", ""), "estimator": ESTIMATOR}
    write_tables(result.margins, MARGIN_COLUMNS, {"csv": margins}, constants=run)
    write_tables(result.rows, INTERVENTION_COLUMNS, {"csv": out}, constants=run)
    return result.rows


def blank_region_rows(rows: list[dict]) -> list[dict]:
    """NaN copies, for the glass and non_glass regions, of the ``all`` rows of a frame
    without a material mask, with the reason."""
    from ..audit.ground_truth import NO_MATERIAL_MASK
    from ..statistics.regions import REGIONS

    return [
        {**row, "region": region, "value": float("nan"), "n_pixels": 0, "reason": NO_MATERIAL_MASK}
        for row in rows
        if row["region"] == "all"
        for region in REGIONS[1:]
    ]


def sensor_rows(renders_l, renders_r, ground_truth_left, sensor: dict, *, label, **options):
    """Table 3's metrics on simulated sensor frames around each view's seed mean.

    Each view gets as many frames as it has seeds, drawn from its own stream
    (``controls.sensor.seed``, the scene, the view), so only the clean image is shared
    between views.
    """
    from ..controls.sensor import SensorFrames, SensorModel
    from ..estimators.seeds import StreamingVariance
    from ..intervention.metrics import intervention_metrics
    from ..seeding import derive_seed

    model = SensorModel(**{k: sensor[k] for k in ("gain", "read_noise", "seed") if k in sensor})
    frames = {}
    for view, renders in (("left", renders_l), ("right", renders_r)):
        acc = StreamingVariance()
        for image in renders:
            acc.update(image)
        seed = (int(model.seed), derive_seed("sensor-intervention", label, view))
        frames[view] = SensorFrames(acc.mean, len(renders), model, seed)
        if frames[view].n_floored:
            log.info(
                "sensor %s: %d seed-mean entries <= 0 floored at 0", view, frames[view].n_floored
            )
    result = intervention_metrics(
        frames["left"], frames["right"], ground_truth_left, margin_samples=0, **options
    )
    for row in result.rows:
        row["source"] = "sensor"
    return result.rows


def intervention_table_job(inputs, outputs: dict) -> list[dict]:
    """Table 3: mean ± std across scenes of each metric, normal and decorrelated, with the
    relative change ``(normal - decorrelated) / |decorrelated|``."""
    from ..io.tables import read_rows, write_tables
    from ..statistics.summary import intervention_table

    required = ("scene", "cost", "metric", "region")
    rows = [r for path in inputs for r in read_rows(path, required=required)]
    table = intervention_table(rows)
    columns = list(table[0]) if table else ["cost", "metric", "region"]
    write_tables(
        table,
        columns,
        outputs,
        caption="Residual-shuffle intervention (Table 3)",
        constants=run_of(rows),
    )
    return table
