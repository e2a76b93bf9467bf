"""Jobs of ``workflow/rules/probe.smk``: train one probe network, test every network of a
fold on its held-out scenes, and write the probe table, figure and verdict."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .common import log, view_stack

PROBE_REGIONS = ("all", "non_glass", "glass")
"""Regions scored (``all`` only where the ground truth has no glass pixel)."""


def _scene(stores: dict, scene: str):
    """The renders (N, H, W, 3) of each view, the left ground truth and its sign."""
    from ..io.store import load_store

    left = view_stack(stores[f"left_{scene}"])[0]
    right = view_stack(stores[f"right_{scene}"])[0]
    gt = load_store(
        stores[f"gt_{scene}"], "ground-truth store", ["disparity", "valid", "glass"]
    ).sel(view="left")
    sign = int(gt.attrs["disparity_sign"])
    truth = {k: gt[k].transpose("y", "x").values for k in ("disparity", "valid", "glass")}
    return left, right, truth, sign


def train_job(stores: dict, out, *, scenes, condition, fold, seed, training: dict) -> dict:
    """Train one network of ``condition`` on ``scenes`` (the fold's training scenes) with
    training seed ``seed`` and save it with its settings
    (:func:`stereovar.probe.training.save_matcher`).

    ``stores`` maps ``left_{scene}`` and ``right_{scene}`` to render-store paths and
    ``gt_{scene}`` to the scene's ground-truth store."""
    from ..probe.experiment import training_frames
    from ..probe.training import TrainSettings, save_matcher, train_matcher

    settings = TrainSettings(**training)
    frames = []
    for scene in scenes:
        left, right, truth, sign = _scene(stores, scene)
        frames += training_frames(left, right, truth, sign=sign)
    net, history = train_matcher(frames, settings, seed=int(seed))
    losses = [x for x in history["loss"] if math.isfinite(x)]
    tail = losses[-max(1, len(losses) // 10) :]
    meta = {
        "condition": condition,
        "fold": int(fold),
        "scenes": list(scenes),
        "frames": len(frames),
        "seconds": history["seconds"],
        "step_seconds": history["step_seconds"],
        "loss_first": float(np.mean(losses[: len(tail)])) if losses else math.nan,
        "loss_last": float(np.mean(tail)) if losses else math.nan,
        "triplets_per_step": float(np.mean(history["triplets"])),
    }
    save_matcher(out, net, settings=settings, seed=int(seed), meta=meta)
    log.info(
        "probe %s fold %s seed %s: %d frames of %s, %d steps in %.1f s (%.0f ms/step), "
        "loss %.4f -> %.4f",
        condition,
        fold,
        seed,
        len(frames),
        ", ".join(scenes),
        settings.steps,
        history["seconds"],
        1000 * history["step_seconds"],
        meta["loss_first"],
        meta["loss_last"],
    )
    return meta


def max_disparity(truths, *, fixed=None, margin: int = 4) -> int:
    """:math:`D`: ``fixed``, or the largest ground-truth disparity plus ``margin``."""
    if fixed is not None:
        return int(fixed)
    top = max(float(np.nanmax(np.where(t["valid"], t["disparity"], np.nan))) for t in truths)
    return int(math.ceil(top)) + int(margin)


def test_job(
    stores: dict,
    networks,
    out,
    *,
    scenes,
    tested,
    test: dict,
    max_disparity_fixed=None,
    disparity_margin: int = 4,
    threads: int = 1,
) -> int:
    """Score every network in ``networks`` (the tested condition's and the control's, of one
    fold) on every test input of the fold's held-out ``scenes``, rendered under ``tested``;
    the per-tile sums go to ``out`` (:data:`stereovar.probe.metrics.TILE_COLUMNS`). Torch
    runs ``threads`` threads (one per job: more spin on a machine whose cores are busy)."""
    import torch

    from ..io.tables import write_tables
    from ..probe.experiment import TestSettings, test_scene
    from ..probe.metrics import TILE_COLUMNS
    from ..probe.training import load_matcher

    torch.set_num_threads(int(threads))
    nets = {}
    for path in networks:
        net, record = load_matcher(path)
        nets[(record["meta"]["condition"], int(record["seed"]))] = net
    data = {scene: _scene(stores, scene) for scene in scenes}
    d_max = max_disparity(
        [truth for _, _, truth, _ in data.values()],
        fixed=max_disparity_fixed,
        margin=disparity_margin,
    )
    settings = TestSettings(**{**test, "max_disparity": d_max})
    rows = []
    for scene, (left, right, truth, sign) in data.items():
        regions = PROBE_REGIONS if np.asarray(truth["glass"]).any() else ("all",)
        scene_rows = test_scene(
            nets, left, right, truth, scene=scene, sign=sign, regions=regions, settings=settings
        )
        rows += [{"tested": tested, **r} for r in scene_rows]
        log.info(
            "probe test of %s on %s: %d networks x %d inputs x %d frames, D = %d",
            tested,
            scene,
            len(nets),
            len(settings.inputs),
            min(settings.test_frames, left.shape[0]),
            d_max,
        )
    write_tables(rows, list(TILE_COLUMNS), {"csv": out})
    return len(rows)


def probe_table_job(
    tiles, outputs: dict, *, figure, verdict, reps: int = 1000, seed: int = 0, source="",
    runs: list | None = None,
) -> list[dict]:
    """The probe table, its figure and the verdict JSON from every test job's tiles."""
    import pandas as pd

    from ..io.store import write_file
    from ..io.tables import write_tables
    from ..probe.metrics import INTERVAL_METHOD, probe_rows
    from ..probe.verdict import probe_verdict
    from .common import save_figure

    frames = [pd.read_csv(p) for p in tiles]
    table = pd.concat(frames, ignore_index=True)
    rows = probe_rows(table, reps=int(reps), seed=int(seed))
    columns = list(rows[0]) if rows else []
    write_tables(
        rows,
        columns,
        outputs,
        caption=(
            "The learned probe (MC-CNN fast, WTA): accuracy (|d - d_GT| < 1 px), end-point "
            "error, the drop from the normal input, the difference in differences (DiD) of that "
            "drop against the sensor_only network on the same inputs, and for the cue conflict "
            f"the share of pixels at d + k; {INTERVAL_METHOD}"
        ),
        constants={"source": source} if source else None,
    )
    result = probe_verdict(rows)
    result["source"] = source
    result["runs"] = list(runs or [])
    text = json.dumps(_clean(result), indent=2) + "\n"
    write_file(Path(verdict), lambda tmp: Path(tmp).write_text(text))
    from ..figures.probe import probe_figure

    save_figure(probe_figure(rows), figure)
    log.info("%s", result["paragraph"])
    return rows


def _clean(value):
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_clean(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
