"""Benchmark: which optimiser trains the probe's matcher better within its step budget.

Run with ``.venv/bin/python bench/probe_optimiser.py`` after ``pip install -e .[probe]``.
MC-CNN fast (Žbontar & LeCun 2016) trains with SGD, momentum 0.9, learning rate 0.003; the
probe's default is Adam at 1e-3 (:class:`stereovar.probe.training.TrainSettings`). Both train
the same seeded network for ``--steps`` steps (the default 200, the probe's budget) on the
synthetic pairs of ``bench/probe.py`` (a smooth random texture resampled through a known
1-13 px disparity field) and are scored on held-out pairs by WTA accuracy
(:math:`|\\hat d - d| < 1` px) over disparities :math:`0..D`.

``--run DIR`` trains on a finished probe run's own renders instead (``DIR`` holds its
``results/``; e.g. the probe preset's): the raw renders (condition ``none``) of fold 0's
training scenes under the probe's split (:func:`stereovar.probe.experiment.fold_scenes`,
``--folds``), scored on the first seed pair of its held-out scenes (the ``normal`` input).

The named baseline is the reference's SGD. Prints each optimiser's accuracy (median over
``--seeds`` training seeds, with their range) and the ratio Adam / SGD, and the same for the
final training loss.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

import numpy as np
from probe import SIGN, synthetic_frame

from stereovar.probe.network import wta_disparity
from stereovar.probe.training import TrainingFrame, TrainSettings, train_matcher


def accuracy(net, pairs, max_disparity: int) -> float:
    """WTA accuracy over every scored pixel of the held-out pairs."""
    hits = total = 0
    for left, right, d, sign in pairs:
        d_hat = wta_disparity(net, left, right, sign=sign, max_disparity=max_disparity)
        ok = np.isfinite(d) & np.isfinite(d_hat)
        hits += int((np.abs(d_hat[ok] - d[ok]) < 1.0).sum())
        total += int(ok.sum())
    return hits / total


def run_pairs(run: Path, scenes, spp: int, folds: int):
    """Training frames of fold 0 and held-out pairs ``(left, right, d)`` of a finished run."""
    from stereovar.jobs.probe import _scene
    from stereovar.layout import ground_truth_store, render_store
    from stereovar.probe.experiment import fold_scenes, scored_disparity, training_frames
    from stereovar.probe.inputs import network_input

    train, test = fold_scenes(scenes, folds)[0]

    def stores(scene):
        out = {f"gt_{scene}": run / ground_truth_store("mitsuba", scene)}
        for view in ("left", "right"):
            folder = (run / render_store("mitsuba", scene, view, spp, "x")).parent
            out[f"{view}_{scene}"] = sorted(folder.glob("seeds*.zarr"))
        return out

    frames, held_out = [], []
    for scene in train:
        left, right, truth, sign = _scene(stores(scene), scene)
        frames += training_frames(left, right, truth, sign=sign)
    for scene in test:
        left, right, truth, sign = _scene(stores(scene), scene)
        d = scored_disparity(truth, sign=sign)
        held_out.append((network_input(left[0]), network_input(right[0]), d, sign))
    return frames, held_out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--height", type=int, default=180)
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--frames", type=int, default=4, help="training frames")
    parser.add_argument("--test-frames", type=int, default=2)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--seeds", type=int, default=3, help="training seeds per optimiser")
    parser.add_argument("--max-disparity", type=int, default=17)
    parser.add_argument("--sgd-lr", type=float, default=0.003, help="MC-CNN fast's rate")
    parser.add_argument("--run", type=Path, help="a finished probe run's folder")
    parser.add_argument("--scenes", type=int, default=8, help="the run's scenes (scene_000...)")
    parser.add_argument("--spp", type=int, default=32, help="the run's SPP")
    parser.add_argument("--folds", type=int, default=2, help="the run's probe.folds")
    args = parser.parse_args(argv)

    if args.run:
        scenes = [f"scene_{k:03d}" for k in range(args.scenes)]
        frames, held_out = run_pairs(args.run, scenes, args.spp, args.folds)
        what = f"{len(frames)} frames of {args.run}, fold 0 of {args.folds}"
    else:
        make = lambda k: (*synthetic_frame(args.height, args.width, 1.0, 13.0, seed=k), SIGN)  # noqa: E731
        frames = [TrainingFrame(*make(k)) for k in range(args.frames)]
        held_out = [make(1000 + k) for k in range(args.test_frames)]
        what = (
            f"{args.frames} training and {args.test_frames} held-out synthetic {args.width}x"
            f"{args.height} pairs (disparity 1-13 px)"
        )
    optimisers = {
        "sgd": TrainSettings(steps=args.steps, optimiser="sgd", learning_rate=args.sgd_lr),
        "adam": TrainSettings(steps=args.steps, optimiser="adam", learning_rate=1e-3),
    }
    print(f"{what}, {args.steps} steps, {args.seeds} seeds")
    result = {}
    for name, settings in optimisers.items():
        acc, loss = [], []
        for seed in range(args.seeds):
            net, history = train_matcher(frames, settings, seed=seed)
            acc.append(accuracy(net, held_out, args.max_disparity))
            loss.append(float(np.mean(history["loss"][-20:])))
        result[name] = (statistics.median(acc), statistics.median(loss))
        label = "(baseline)" if name == "sgd" else ""
        print(
            f"  {name:4s} lr {settings.learning_rate:g} {label:10s}: held-out WTA accuracy "
            f"{result[name][0]:.3f} [{min(acc):.3f}, {max(acc):.3f}], final loss "
            f"{result[name][1]:.3f}"
        )
    print(f"  ratio accuracy adam / sgd: {result['adam'][0] / result['sgd'][0]:.2f}")
    print(f"  ratio final loss adam / sgd: {result['adam'][1] / result['sgd'][1]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
