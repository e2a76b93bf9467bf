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
    "cost",
    "metric",
    "region",
    "condition",
    "value",
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
) -> list[dict]:
    """Table 3's metrics of one scene, normal against decorrelated (paper Sec. 3.4), and a
    sample of the per-pixel GT margins for the distribution figure."""
    import math

    from ..intervention.metrics import intervention_metrics
    from ..io.renders import LazyRenders, RenderStore
    from ..io.store import open_dataset
    from ..io.tables import write_tables

    gt = open_dataset(ground_truth)
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
    renders_l, renders_r = LazyRenders(left), LazyRenders(right)
    result = intervention_metrics(
        renders_l,
        renders_r,
        gl,
        sign=int(gt.attrs["disparity_sign"]),
        max_disparity=int(max_disparity),
        window=window,
        block=block,
        seed=seed,
        margin_samples=margin_samples,
        workers=workers,
    )
    attrs = RenderStore(left[0]).attrs
    scene = attrs.get("scene", gt.attrs.get("scene"))
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
            "%-13s %-13s %-9s %-12s %.4g (chance %.4g, n=%d)%s",
            row["cost"],
            row["metric"],
            row["region"],
            row["condition"],
            row["value"],
            row["chance"],
            row["n_pixels"],
            f" [{row['reason']}]" if row["reason"] else "",
        )
    for sample in result.margins:
        sample["scene"] = scene
    run = {"renderer": attrs.get("renderer", ""), "estimator": ESTIMATOR}
    write_tables(result.margins, MARGIN_COLUMNS, {"csv": margins}, constants=run)
    write_tables(result.rows, INTERVENTION_COLUMNS, {"csv": out}, constants=run)
    return result.rows


def intervention_table_job(inputs, outputs: dict) -> list[dict]:
    """Table 3: mean ± std across scenes of each metric, normal and decorrelated, with the
    relative change (normal - decorrelated) / |decorrelated|."""
    from ..io.tables import read_rows, write_tables
    from ..statistics.summary import intervention_table

    rows = [r for path in inputs for r in read_rows(path)]
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
