"""Job of ``workflow/rules/ground_truth.smk``: trace and store one scene's ground truth."""

from __future__ import annotations

import json

from .common import log, prepare_scene


def ground_truth_job(
    spec,
    out,
    *,
    renderer="mitsuba",
    variant="auto",
    width,
    height,
    baseline_m,
    convention,
    threads=None,
) -> None:
    """Trace and store the ground truth of one scene (``results/ground_truth/{scene}.zarr``)."""
    from ..ground_truth import compute_ground_truth, summarize_ground_truth
    from ..io.store import write_dataset

    prepared = prepare_scene(
        spec,
        renderer=renderer,
        variant=variant,
        width=width,
        height=height,
        baseline_m=baseline_m,
        convention=convention,
        threads=threads,
    )
    ds = compute_ground_truth(prepared, attrs=prepared.provenance)
    write_dataset(ds, out)
    summary = summarize_ground_truth(ds)
    log.info("ground truth: %s", json.dumps({k: round(v, 4) for k, v in summary.items()}))
