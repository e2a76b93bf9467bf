"""Job of ``workflow/rules/ground_truth.smk``: trace and store one scene's ground truth."""

from __future__ import annotations

import json

from .common import log, prepare_scene


def ground_truth_job(spec, out, *, renderer="mitsuba", variant="auto", threads=None, **rig):
    """Trace and store the ground truth of one scene (``results/ground_truth/{scene}.zarr``).

    ``rig`` holds ``width``, ``height``, ``baseline_m`` and ``convention``.
    """
    from ..ground_truth import compute_ground_truth, summarize_ground_truth
    from ..io.store import write_dataset

    prepared = prepare_scene(spec, renderer=renderer, variant=variant, threads=threads, **rig)
    ds = compute_ground_truth(prepared, attrs=prepared.provenance)
    write_dataset(ds, out)
    summary = summarize_ground_truth(ds)
    log.info("ground truth: %s", json.dumps({k: round(v, 4) for k, v in summary.items()}))
