"""Benchmark: one 1280x720 SAD cost volume (5x5, D = 64) + WTA against OpenCV's StereoBM.

Run with ``python bench/cost_volume.py`` after ``pip install -e .[bench]`` (OpenCV). Both
paths get the same synthetic 8-bit textured pair whose right view is the left shifted by a
known integer disparity under OpenCV's convention :math:`x_R = x_L - d` (``sign=-1``).
The stereovar paths are the full volume (the reference), the streamed scan in float32, the
streamed scan in exact integers (the 8-bit pair as is) and the scan the intervention runs:
float64 with the GT margin and hit counts. Peak memory is measured with :mod:`tracemalloc`
(numpy reports its buffers there). Every ratio is against StereoBM timed in the same run.
"""

from __future__ import annotations

import argparse
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

from stereovar.intervention.scan import scan_cost_volume, wta_disparity

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the tests' references
from tests.reference.costvolume import sad_cost_volume  # noqa: E402


def textured_pair(height: int, width: int, shift: int, seed: int = 0):
    """8-bit random texture and its copy shifted so that ``R(x - shift) = L(x)``."""
    rng = np.random.default_rng(seed)
    left = rng.integers(0, 256, size=(height, width), dtype=np.uint8)
    right = rng.integers(0, 256, size=(height, width), dtype=np.uint8)
    right[:, : width - shift] = left[:, shift:]
    return left, right


def wta_full(left, right, max_disparity, window):
    """Full float32 volume (float64 sums), then argmin over scored disparities."""
    cost, scored = sad_cost_volume(
        left, right, max_disparity=max_disparity, window=window, sign=-1, dtype=np.float32
    )
    np.copyto(cost, np.inf, where=~scored)
    disp = cost.argmin(axis=0)
    disp[~scored.any(axis=0)] = -1
    return disp


def wta_streaming(left, right, max_disparity, window, dtype=np.float32):
    """Strip-blocked threaded scan (:func:`stereovar.intervention.scan.wta_disparity`)."""
    disp, _ = wta_disparity(
        left,
        right,
        max_disparity=max_disparity,
        window=window,
        sign=-1,
        dtype=dtype,
        workers=2,
    )
    return disp


def margin_scan(left, right, max_disparity, window, d_gt):
    """The intervention's scan: float64 WTA, GT margin and hit counts."""
    return scan_cost_volume(
        left, right, max_disparity=max_disparity, window=window, sign=-1, d_gt=d_gt, workers=2
    ).disparity


def timed(fn, repeats):
    times = []
    out = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def peak_bytes(fn):
    tracemalloc.start()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--height", type=int, default=720)
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--max-disparity", type=int, default=64)
    parser.add_argument("--window", type=int, default=5)
    parser.add_argument("--shift", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)

    left, right = textured_pair(args.height, args.width, args.shift)
    lf, rf = left.astype(np.float32), right.astype(np.float32)
    D, w = args.max_disparity, args.window
    r = w // 2
    # Pixels where the true match and its whole window are inside both images.
    core = (slice(r, args.height - r), slice(r + args.shift, args.width - r))
    print(f"image {args.width}x{args.height}, window {w}x{w}, D = {D} ({D + 1} disparities)")

    t_full, disp = timed(lambda: wta_full(lf, rf, D, w), args.repeats)
    acc = np.mean(disp[core] == args.shift)
    mem_full = peak_bytes(lambda: wta_full(lf, rf, D, w))
    print(
        f"stereovar full volume + WTA : {t_full * 1e3:8.1f} ms  peak {mem_full / 2**20:7.1f} MiB"
        f"  (accuracy at core pixels {acc:.4f})"
    )
    d_gt = np.full(left.shape, float(args.shift))
    paths = {
        "streamed WTA, float32": lambda: wta_streaming(lf, rf, D, w),
        "streamed WTA, exact int16": lambda: wta_streaming(left, right, D, w, dtype=None),
        "streamed WTA + GT margin, float64": lambda: margin_scan(
            left.astype(np.float64), right.astype(np.float64), D, w, d_gt
        ),
    }
    times = {}
    for name, fn in paths.items():
        times[name], disp_s = timed(fn, args.repeats)
        assert np.array_equal(disp_s, disp), f"{name} and the full-volume WTA disagree"
        print(
            f"stereovar {name:34s}: {times[name] * 1e3:8.1f} ms  peak "
            f"{peak_bytes(fn) / 2**20:7.1f} MiB"
        )

    try:
        import cv2
    except ImportError:
        print("OpenCV not installed; for the StereoBM comparison run: pip install -e .[bench]")
        return 0
    bm = cv2.StereoBM_create(numDisparities=64, blockSize=5)
    t_bm, raw = timed(lambda: bm.compute(left, right), max(args.repeats, 10))
    disp_bm = raw.astype(np.float64) / 16.0
    acc_bm = np.mean(np.abs(disp_bm[core] - args.shift) < 1)
    print(
        f"OpenCV StereoBM (64 disp.)  : {t_bm * 1e3:8.1f} ms  ({cv2.getNumThreads()} threads, "
        f"accuracy at core pixels {acc_bm:.4f})"
    )
    print(f"ratio full volume / StereoBM{'':20s}: {t_full / t_bm:6.1f}x")
    for name, t in times.items():
        print(f"ratio {name:40s}: {t / t_bm:6.1f}x  (goal <= 5x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
