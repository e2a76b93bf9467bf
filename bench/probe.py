"""Benchmark: the learned matcher's training step and inference, each against a named baseline.

Run with ``.venv/bin/python bench/probe.py`` after ``pip install -e .[probe]`` (PyTorch on
the CPU); ``--large`` adds the inference timing at 1280x720. Every pair is synthetic: a
smooth random texture (the right view) and the left view resampled from it through a known
disparity field of 1-13 px (``sign=-1``, right pixel at :math:`x - d`), both passed through
the matcher's input encoding (:func:`stereovar.probe.inputs.network_input`). Weights do not
change the timings, so the networks are barely trained.

1. **Training step.** :func:`stereovar.probe.training.train_matcher` (the default
   :class:`~stereovar.probe.training.TrainSettings` crop sizes, 1 thread; its own
   ``step_seconds``: crop and offset sampling, forward, loss, backward, Adam) against the
   named baseline, a bare PyTorch loop on the same batch: the same seeded
   :class:`~stereovar.probe.network.MatchingNet`, one fixed batch of crops and triplet
   columns drawn once before the loop, then per step forward both views,
   ``torch.gather``, hinge loss, backward, Adam step. Prints train_matcher / bare.
2. **Threads.** The same training with ``TrainSettings(threads=2)`` against
   ``threads=1`` (the baseline of 1.): prints the speed-up t(1) / t(2).
3. **Inference.** :func:`stereovar.probe.network.wta_disparity` (dense features once per
   view, one dot product per disparity, argmax) against the named baseline, the hand-built
   SAD cost volume of Table 3 as the intervention runs it
   (:func:`stereovar.intervention.scan.scan_cost_volume`: float64, 5x5 window, WTA and GT
   margin) on the same pair, the same disparities :math:`0..D` (:math:`D` = 13 + the
   config's ``disparity_margin`` 4) and the same threads. Prints seconds per (megapixel x
   disparity) of each and their ratio.

The three training runs alternate within each repeat and every figure is the median over
``--repeats``, so a load that comes and goes on shared cores hits all of them alike; on a
small shared machine the timings are still noisy (a few tens of per cent run to run). When
other jobs keep the cores busy, PyTorch's OpenMP threads spin at their barriers and 2 threads
can be several times slower than 1; ``OMP_WAIT_POLICY=PASSIVE`` in the environment shows
whether that is the cause.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

import numpy as np
import torch

from stereovar.intervention.scan import scan_cost_volume
from stereovar.probe.inputs import network_input
from stereovar.probe.network import FEATURES, MatchingNet, wta_disparity
from stereovar.probe.training import (
    TrainingFrame,
    TrainSettings,
    draw_batch,
    train_matcher,
)

SIGN = -1


def smooth_noise(rng, height: int, width: int, scale: float) -> np.ndarray:
    """Gaussian noise blurred to a correlation length of about ``scale`` px, in [0, 1]."""
    noise = rng.standard_normal((height, width))
    f_y = np.fft.fftfreq(height)[:, None]
    f_x = np.fft.rfftfreq(width)[None, :]
    kernel = np.exp(-2.0 * (np.pi * scale) ** 2 * (f_y**2 + f_x**2))
    field = np.fft.irfft2(np.fft.rfft2(noise) * kernel, s=(height, width))
    field -= field.min()
    return field / field.max()


def synthetic_frame(height: int, width: int, d_min: float, d_max: float, seed: int):
    """A textured pair with a known disparity field: ``L(x, y) = R(x - d(x, y), y)``.

    Returns the network inputs and the left view's disparity (NaN where the match leaves
    the right image)."""
    rng = np.random.default_rng(seed)
    right = 0.15 + 0.7 * smooth_noise(rng, height, width, 1.0)
    disparity = d_min + (d_max - d_min) * smooth_noise(rng, height, width, 30.0)
    cols = np.arange(width, dtype=np.float64)
    left = np.empty_like(right)
    for y in range(height):
        left[y] = np.interp(cols + SIGN * disparity[y], cols, right[y])
    disparity[cols[None, :] + SIGN * disparity < 0] = np.nan
    return network_input(left), network_input(right), disparity.astype(np.float32)


def median_of(values) -> float:
    return float(statistics.median(values))


def train_step_seconds(frames, settings: TrainSettings, seed: int) -> float:
    """Seconds per step of :func:`train_matcher` (its own loop timer)."""
    _, history = train_matcher(frames, settings, seed=seed)
    return float(history["step_seconds"])


def bare_batch(frames, settings: TrainSettings, seed: int):
    """One batch of crops and triplet columns drawn as train_matcher draws them, once."""
    rng = np.random.default_rng([int(seed), 1])
    left, right, c_pos, c_neg, keep = draw_batch(frames, settings, rng)
    idx = lambda c: torch.from_numpy(c)[:, None].expand(-1, FEATURES, -1, -1)  # noqa: E731
    return left, right, idx(c_pos), idx(c_neg), keep


def bare_step_seconds(batch, settings: TrainSettings, seed: int) -> float:
    """Seconds per step of the bare PyTorch loop on one fixed batch."""
    left, right, i_pos, i_neg, keep = batch
    torch.set_num_threads(int(settings.threads))
    torch.manual_seed(int(seed))
    net = MatchingNet()
    opt = torch.optim.Adam(net.parameters(), lr=settings.learning_rate)
    net.train()
    start = time.perf_counter()
    for _ in range(int(settings.steps)):
        fl, fr = net(left), net(right)
        s_pos = (fl * torch.gather(fr, 3, i_pos)).sum(1)[keep]
        s_neg = (fl * torch.gather(fr, 3, i_neg)).sum(1)[keep]
        loss = torch.relu(settings.margin + s_neg - s_pos).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
    return (time.perf_counter() - start) / int(settings.steps)


def inference(net, left, right, d_gt, max_disparity: int, window: int, threads: int, repeats):
    """Median seconds of wta_disparity and of Table 3's scan on one pair."""
    torch.set_num_threads(int(threads))
    scan_args = {
        "max_disparity": max_disparity,
        "window": window,
        "sign": SIGN,
        "d_gt": d_gt,
        "dtype": np.float64,
        "workers": int(threads),
    }
    l64, r64 = left.astype(np.float64), right.astype(np.float64)
    wta_disparity(net, left, right, sign=SIGN, max_disparity=max_disparity)  # warm-up
    t_net, t_scan = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        wta_disparity(net, left, right, sign=SIGN, max_disparity=max_disparity)
        t_net.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        scan_cost_volume(l64, r64, **scan_args)
        t_scan.append(time.perf_counter() - t0)
    return median_of(t_net), median_of(t_scan)


def report_inference(net, height, width, args):
    left, right, d = synthetic_frame(height, width, 1.0, 13.0, seed=args.seed + 100)
    D = args.max_disparity
    t_net, t_scan = inference(net, left, right, d, D, args.window, args.threads, args.repeats)
    unit = height * width / 1e6 * (D + 1)
    print(
        f"inference {width}x{height}, disparities 0..{D}, {args.threads} thread(s), "
        f"median of {args.repeats}:"
    )
    print(
        f"  Table 3 SAD scan ({args.window}x{args.window}, float64, GT margin; baseline): "
        f"{t_scan * 1e3:9.1f} ms  {t_scan / unit * 1e3:8.3f} ms per MP x disparity"
    )
    print(
        f"  wta_disparity (MC-CNN fast, dense)                 : {t_net * 1e3:9.1f} ms  "
        f"{t_net / unit * 1e3:8.3f} ms per MP x disparity"
    )
    print(f"  ratio wta_disparity / SAD scan: {t_net / t_scan:.1f}x")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--height", type=int, default=180)
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--frames", type=int, default=2, help="training frames")
    parser.add_argument("--steps", type=int, default=15, help="training steps per run")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--max-disparity", type=int, default=17, help="D (13 + disparity_margin 4)")
    parser.add_argument("--window", type=int, default=5, help="SAD window side")
    parser.add_argument("--threads", type=int, default=1, help="threads of the inference")
    parser.add_argument("--large", action="store_true", help="also infer at 1280x720")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    frames = [
        TrainingFrame(*synthetic_frame(args.height, args.width, 1.0, 13.0, args.seed + k), SIGN)
        for k in range(args.frames)
    ]
    one = TrainSettings(steps=args.steps, threads=1)
    two = TrainSettings(steps=args.steps, threads=2)
    batch = bare_batch(frames, one, args.seed)
    print(
        f"training on {args.frames} synthetic {args.width}x{args.height} frames (disparity "
        f"1-13 px), {one.crops} crops of {one.crop_rows}x{one.crop_cols} features, "
        f"{args.steps} steps per run, median of {args.repeats} runs; "
        f"{int(batch[4].sum())} triplets in the bare loop's batch"
    )
    train_step_seconds(frames, TrainSettings(steps=2, threads=1), args.seed)  # warm-up
    t_one, t_bare, t_two = [], [], []
    for _ in range(args.repeats):
        t_one.append(train_step_seconds(frames, one, args.seed))
        t_bare.append(bare_step_seconds(batch, one, args.seed))
        t_two.append(train_step_seconds(frames, two, args.seed))
    one_s, bare_s, two_s = median_of(t_one), median_of(t_bare), median_of(t_two)
    print(f"  bare PyTorch loop, fixed batch, 1 thread (baseline): {bare_s * 1e3:8.1f} ms/step")
    print(f"  train_matcher, 1 thread                            : {one_s * 1e3:8.1f} ms/step")
    print(f"  ratio train_matcher / bare loop: {one_s / bare_s:.2f}")
    print(f"  train_matcher, 2 threads                           : {two_s * 1e3:8.1f} ms/step")
    print(f"  speed-up 2 threads over 1 (t1 / t2): {one_s / two_s:.2f}x")

    net, _ = train_matcher(frames, TrainSettings(steps=args.steps), seed=args.seed)
    report_inference(net, args.height, args.width, args)
    if args.large:
        report_inference(net, 720, 1280, args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
