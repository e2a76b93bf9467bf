"""Benchmark: where each probe network's validation accuracy levels off, and what a step costs.

Run with ``.venv/bin/python bench/probe_plateau.py --run DIR`` after a run whose ``results/``
holds the renders (``make run``, or the probe's own run). For each architecture and learning
rate it trains one network, as a ``probe_train`` job does (:func:`stereovar.jobs.probe.train_job`,
condition ``none``, fold 0 of ``--folds``, the config's other training settings), for
``--steps`` steps with a validation check every ``--check-every`` steps and a stop rule that
never fires, then replays the probe's stop rule (:class:`stereovar.probe.convergence.Plateau`
with ``--rule-every`` / ``--patience`` / ``--min-delta`` / ``--min-steps``, the defaults of
``probe.training``) on the recorded checks: the step it would stop at, its best step, the
validation accuracy there and at 300 steps, and the CPU milliseconds per step (its checks and
the reading of the renders included).

The named baseline is learning rate 1e-3, the rate both networks trained at before the
cost-volume network's default became 3e-3; each other rate prints its ratio of steps to the
plateau and its accuracy at 300 steps beside the baseline's.

Usage::

    .venv/bin/python bench/probe_plateau.py --run /path/to/run
    .venv/bin/python bench/probe_plateau.py --run DIR --arch costvolume --rates 1e-3 3e-3 1e-2
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

BASELINE = 1e-3
"""The learning rate every other one is compared with."""


def stores(run: Path, scenes, spp: int) -> dict:
    """``left_{scene}``, ``right_{scene}`` and ``gt_{scene}`` of a finished run's renders."""
    from stereovar.layout import ground_truth_store, render_store

    out = {}
    for scene in scenes:
        out[f"gt_{scene}"] = str(run / ground_truth_store("mitsuba", scene))
        for view in ("left", "right"):
            folder = (run / render_store("mitsuba", scene, view, spp, "x")).parent
            found = sorted(str(p) for p in folder.glob("seeds*.zarr"))
            if not found:
                sys.exit(f"bench/probe_plateau.py: no renders under {folder}; pass --run, "
                         "--spp and --scenes of a finished run")
            out[f"{view}_{scene}"] = found
    return out


def replay(history, *, every: int, patience: int, min_delta: float, min_steps: int):
    """(stop step, best step, best accuracy) of the probe's stop rule on recorded checks,
    reading every check whose step is a multiple of ``every``; the last check when the
    rule never fires (``stop`` is then None)."""
    from stereovar.probe.convergence import Plateau, StopRule

    plateau = Plateau(StopRule(check_every=every, patience=patience, min_delta=min_delta,
                               min_steps=min_steps))
    for step, accuracy in history:
        if step % every:
            continue
        if plateau.update(step, accuracy):
            return step, plateau.best_step, plateau.best_accuracy
    return None, plateau.best_step, plateau.best_accuracy


def at(history, step: int) -> float:
    """The recorded accuracy at ``step`` (the nearest check at or before it)."""
    before = [a for s, a in history if s <= step]
    return before[-1] if before else float("nan")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", type=Path, required=True, help="a finished run's folder")
    parser.add_argument("--scenes", type=int, default=4, help="the run's scenes (scene_000...)")
    parser.add_argument("--spp", type=int, default=32, help="the run's SPP")
    parser.add_argument("--folds", type=int, default=2, help="probe.folds")
    parser.add_argument("--arch", nargs="+", default=["mccnn", "costvolume"])
    parser.add_argument("--rates", nargs="+", type=float, default=[1e-3, 3e-3])
    parser.add_argument("--steps", type=int, default=900)
    parser.add_argument("--check-every", type=int, default=25)
    parser.add_argument("--rule-every", type=int, default=50)
    parser.add_argument("--patience", type=int, default=2)
    parser.add_argument("--min-delta", type=float, default=0.002)
    parser.add_argument("--min-steps", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    import torch

    torch.set_num_threads(1)
    from stereovar.jobs.probe import train_job
    from stereovar.probe.experiment import fold_scenes
    from stereovar.probe.training import load_matcher

    scenes = [f"scene_{i:03d}" for i in range(args.scenes)]
    train, _ = fold_scenes(scenes, args.folds)[0]
    inputs = stores(args.run.resolve(), train, args.spp)
    print(f"fold 0 of {args.folds}: training on {', '.join(train)}; stop rule: a check every "
          f"{args.rule_every} steps, {args.patience} without a gain above "
          f"{100 * args.min_delta:g} points, not before {args.min_steps}")
    print(f"{'network':<11} {'rate':>7} {'stops at':>8} {'best':>5} {'acc best':>8} "
          f"{'acc 300':>7} {'ms/step':>7}  vs rate {BASELINE:g}")
    cwd = os.getcwd()
    for arch in args.arch:
        base = None
        for rate in sorted(args.rates, key=lambda r: r != BASELINE):
            with tempfile.TemporaryDirectory() as tmp:
                out = Path(tmp) / "net.pt"
                start = time.process_time()
                os.chdir(args.run)
                try:
                    train_job(inputs, [str(out)], scenes=train, condition="none", arch=arch,
                              variants=["main"], fold=0, seeds=[args.seed],
                              training={"steps": args.steps, "check_every": args.check_every,
                                        "patience": 10**6, "min_steps": 0,
                                        "learning_rate": rate})
                finally:
                    os.chdir(cwd)
                cpu = time.process_time() - start
                meta = load_matcher(out)[1]["meta"]
            history = [(int(s), float(a)) for s, a in meta["validation"]]
            stop, best, accuracy = replay(history, every=args.rule_every,
                                          patience=args.patience, min_delta=args.min_delta,
                                          min_steps=args.min_steps)
            ms = 1000 * cpu / args.steps
            row = (stop or args.steps, at(history, 300))
            ratio = ""
            if rate == BASELINE:
                base = row
            elif base is not None:
                ratio = (f"steps {row[0] / base[0]:.2f}x, accuracy at 300 "
                         f"{100 * (row[1] - base[1]):+.1f} points")
            print(f"{arch:<11} {rate:>7g} {stop if stop else 'never':>8} {best:>5} "
                  f"{100 * accuracy:>7.1f}% {100 * row[1]:>6.1f}% {ms:>7.0f}  {ratio}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
