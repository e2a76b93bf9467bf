"""Job of ``stereovar probe`` and ``workflow/rules/probe_model.smk``: the user's own network
on the counterfactual inputs of every frame (:mod:`stereovar.probe.user_model`)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .common import log, view_stack

TABLE_CAPTION = (
    "The user's network on the counterfactual inputs: accuracy (|d - d_GT| < 1 px) and "
    "end-point error per input; mc_shuffle: drop of accuracy and rise of EPE when the right "
    "view's Monte Carlo residual is shuffled within intensity strata (normal -> shuffled); "
    "camera_shuffle: the same shuffle of camera-law noise at the renders' level (camera -> "
    "camera_shuffled); mc_minus_camera: their difference, the part only the residual's "
    "cross-view alignment explains; nonfinite_share: share of the scored pixels where the "
    "model's disparity is NaN or Inf, each a miss at an end-point error of the frame's largest "
    "disparity (at least 1 px), and its rise under each shuffle; constant: the best constant "
    "answers of each frame (the accuracy of the centre of the densest 2-px window of ground "
    "truth, the EPE of its median), the same for every input; over_constant: the network's "
    "gain over them on the renders (accuracy normal - constant, EPE constant - normal). "
    "Intervals: percentile, tile bootstrap stratified by frame"
)


def frame_data(stores: dict, scene: str):
    """The renders (N, H, W, 3) of each view, the left view's ``disparity`` and ``valid``,
    and the sign, from ``left_{scene}``, ``right_{scene}`` and ``gt_{scene}`` of ``stores``
    (each view's render stores, a path or a list of paths, and the ground-truth store)."""
    from ..io.store import load_store

    def paths(value):
        return [value] if isinstance(value, (str, Path)) else list(value)

    left = view_stack(paths(stores[f"left_{scene}"]))[0]
    right = view_stack(paths(stores[f"right_{scene}"]))[0]
    gt = load_store(stores[f"gt_{scene}"], "ground-truth store", ["disparity", "valid"])
    truth = {k: gt[k].sel(view="left").transpose("y", "x").values for k in ("disparity", "valid")}
    return left, right, truth, int(gt.attrs["disparity_sign"])


def probe_model_job(
    stores: dict,
    outputs: dict,
    *,
    scenes,
    factory: str,
    weights,
    device: str = "cpu",
    settings: dict | None = None,
    source: str = "",
    threads: int | None = None,
    model=None,
) -> dict:
    """Run the user's model (``factory`` with ``weights``, or an already loaded ``model``) on
    the four inputs of every frame in ``scenes``, write the table to ``outputs`` (paths by
    format, :func:`stereovar.io.tables.write_tables`; a ``json`` key gets the record) and
    return the record: ``model``, ``weights``, ``reading``, ``rows``, ``lines`` (accuracy
    and EPE of every input beside the best constant's,
    :func:`~stereovar.probe.user_summary.model_lines`), ``checks``
    (:func:`~stereovar.probe.user_checks.testability`), ``testable`` and ``warnings``.

    ``settings`` are :class:`~stereovar.probe.user_model.ModelSettings` fields. One
    ``warning:`` line each when the model returned NaN or Inf at any scored pixel (the share
    of each input, :func:`~stereovar.probe.user_summary.nonfinite_warning`), when its
    accuracy on the ``normal`` input is under 5 % and when it is not testable (its output does
    not respond to its input or it is no better than a constant disparity,
    :func:`~stereovar.probe.user_checks.testability_warning`); the reading then says *not
    testable* instead of *no use*."""
    import torch

    from ..io.store import write_file
    from ..io.tables import write_tables
    from ..probe.experiment import check_renders
    from ..probe.user_checks import shift_response, testability, testability_warning
    from ..probe.user_loading import load_user_model
    from ..probe.user_model import ModelSettings, frame_law, score_frame
    from ..probe.user_summary import model_lines, model_reading, model_rows, nonfinite_warning

    if threads:
        torch.set_num_threads(int(threads))
    if model is None:
        model = load_user_model(factory, weights, device=device)
    config = ModelSettings(**(settings or {}))
    rows = []
    for scene in scenes:
        left, right, truth, sign = frame_data(stores, scene)
        check_renders(left.shape[0], f"frame {scene}'s renders per view")
        law = frame_law(left, truth["valid"])
        frame_rows = score_frame(
            model,
            left,
            right,
            truth,
            scene=scene,
            sign=sign,
            law=law,
            settings=config,
            device=device,
        )
        rows += frame_rows
        normal = [r for r in frame_rows if r["test_input"] == "normal"]
        n = sum(r["n"] for r in normal)
        log.info(
            "probe model %s on %s: %d test renders x 4 inputs, normal accuracy %.4f",
            factory,
            scene,
            min(config.test_frames, left.shape[0]),
            sum(r["hits"] for r in normal) / n if n else float("nan"),
        )
    table = model_rows(rows, reps=config.reps, seed=config.seed, level=config.level)
    checks = testability(table, shift_response(rows))
    reading = model_reading(table, checks)
    warnings = [nonfinite_warning(table)]
    if np.nanmedian([r["accuracy"] for r in table[:1]]) < 0.05:
        warnings.append(
            "the model's accuracy on the renders is under 5 %: check its output is disparity "
            "(positive, in pixels; RAFT-Stereo's flow is -d) in the conventional sign"
        )
    warnings = [w for w in (*warnings, testability_warning(checks)) if w]
    for warning in warnings:
        log.warning("warning: %s", warning)
    formats = {k: v for k, v in outputs.items() if k != "json"}
    if formats:
        write_tables(
            table,
            list(table[0]),
            formats,
            caption=TABLE_CAPTION,
            constants={
                **({"source": source} if source else {}),
                "model": factory,
                "testable": "yes" if checks["testable"] else f"no: {checks['problem']}",
            },
        )
    lines = model_lines(table)
    record = {
        "model": factory,
        "weights": str(weights),
        "reading": reading,
        "testable": checks["testable"],
        "checks": checks,
        "warnings": warnings,
        "lines": lines,
        "rows": table,
    }
    if outputs.get("json"):
        text = json.dumps(record, indent=2, default=float) + "\n"
        write_file(Path(outputs["json"]), lambda tmp: Path(tmp).write_text(text))
    for line in lines:
        log.info("%s", line)
    log.info("%s", reading)
    return record


def frames_manifest(source: str) -> str:
    """Where ``probe_model_frames`` lists the frames' stores of a source:
    ``results/{source}/probe_model/frames.json``."""
    from ..layout import RESULTS

    return f"{RESULTS}/{source}/probe_model/frames.json"


def write_manifest(stores: dict, scenes, out) -> None:
    """Write the frames (``scenes``) and their stores (:func:`frame_data`'s keys) as JSON."""
    from ..io.store import write_file

    def plain(value):
        return str(value) if isinstance(value, (str, Path)) else [str(v) for v in value]

    record = {"scenes": list(scenes), "stores": {k: plain(v) for k, v in stores.items()}}
    text = json.dumps(record, indent=2) + "\n"
    write_file(Path(out), lambda tmp: Path(tmp).write_text(text))


def read_manifest(path) -> tuple[list, dict]:
    """The frames and their stores written by :func:`write_manifest`."""
    record = json.loads(Path(path).read_text())
    return record["scenes"], record["stores"]
