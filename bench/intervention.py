"""Benchmark: the Sec. 3.4 intervention of one scene at the paper's scale, streamed.

Run with ``python bench/intervention.py``. A synthetic scene at 1280x720 with N = 30 seeds is
generated seed by seed (a smooth clean image plus noise; the right view is the left shifted
by a known disparity field), so the renders are never all in memory, exactly as the workflow
reads its stores. It times :func:`stereovar.intervention.metrics.intervention_metrics` (streamed
scans, 2 threads) and, as the named baseline in the same run, the full-volume reference for
one seed: the dense ``sad_cost_volume`` + ``gt_margin`` + ``wta_accuracy`` of C_ε
(``tests/reference/costvolume.py``), which the streamed path replaces. Peak
memory is measured with :mod:`tracemalloc` (numpy reports its buffers there).
"""

from __future__ import annotations

import argparse
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

from stereovar.intervention.metrics import intervention_metrics
from stereovar.intervention.scan import scan_cost_volume

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the tests' references
from tests.reference.costvolume import gt_margin, sad_cost_volume, wta_accuracy  # noqa: E402


class SyntheticRenders:
    """Seed ``k`` of one view, generated on demand: clean image + independent noise."""

    def __init__(self, clean, n_seeds, seed):
        self.clean, self.n, self.seed = clean, n_seeds, seed

    def __len__(self):
        return self.n

    def __getitem__(self, k):
        if k >= self.n:
            raise IndexError(k)
        rng = np.random.default_rng([self.seed, k])
        noise = rng.standard_normal(self.clean.shape, dtype=np.float32)
        return self.clean + 0.05 * noise * self.clean


def scene(height, width, shift):
    yy, xx = np.mgrid[0:height, 0 : width + shift].astype(np.float32)
    base = 0.5 + 0.3 * np.sin(xx / 7.0) * np.cos(yy / 11.0)
    base = np.repeat(base[..., None], 3, axis=2)
    left, right = base[:, shift:], base[:, :width]  # x_R = x_L + shift
    gt = {
        "disparity": np.full((height, width), float(shift)),
        "valid": np.ones((height, width), bool),
        "glass": np.zeros((height, width), bool),
    }
    gt["glass"][height // 4 : height // 2, width // 4 : width // 2] = True
    return np.ascontiguousarray(left), np.ascontiguousarray(right), gt


def measure(fn):
    tracemalloc.start()
    t0 = time.perf_counter()
    out = fn()
    elapsed = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return elapsed, peak, out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--height", type=int, default=720)
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--seeds", type=int, default=30)
    parser.add_argument("--max-disparity", type=int, default=30)
    parser.add_argument("--shift", type=int, default=12)
    args = parser.parse_args(argv)

    clean_l, clean_r, gt = scene(args.height, args.width, args.shift)
    left = SyntheticRenders(clean_l, args.seeds, 1)
    right = SyntheticRenders(clean_r, args.seeds, 2)
    D = args.max_disparity
    print(f"{args.width}x{args.height}, N = {args.seeds}, D = {D}, window 5, blocks 16, 2 threads")

    eps_l = left[0].mean(axis=-1) - clean_l.mean(axis=-1)
    eps_r = right[0].mean(axis=-1) - clean_r.mean(axis=-1)
    d_gt = gt["disparity"]

    def full_volume():
        cost, scored = sad_cost_volume(eps_l, eps_r, max_disparity=D, window=5, sign=1)
        return gt_margin(cost, scored, d_gt), wta_accuracy(cost, scored, d_gt, gt["valid"])

    def streamed():
        return scan_cost_volume(
            eps_l, eps_r, max_disparity=D, window=5, sign=1, d_gt=d_gt, workers=2
        )

    t_full, m_full, (margin, _) = measure(full_volume)
    t_scan, m_scan, scan = measure(streamed)
    np.testing.assert_allclose(scan.margin, margin, rtol=1e-9, atol=1e-12, equal_nan=True)
    print(
        f"one seed's C_eps, full volume (baseline): {t_full:7.2f} s  peak {m_full / 2**20:7.1f} MiB"
    )
    print(
        f"one seed's C_eps, streamed scan         : {t_scan:7.2f} s  peak {m_scan / 2**20:7.1f} MiB"
    )
    print(f"ratio streamed / full volume: time {t_scan / t_full:.2f}, memory {m_scan / m_full:.3f}")

    t_all, m_all, result = measure(
        lambda: intervention_metrics(
            left, right, gt, sign=1, max_disparity=D, window=5, block=16, workers=2
        )
    )
    wta = next(
        r
        for r in result.rows
        if (r["cost"], r["metric"], r["region"], r["condition"])
        == ("residual_sad", "wta_accuracy", "non_glass", "normal")
    )
    print(
        f"whole scene (2 x {args.seeds} C_eps scans + C_sigma + peak): {t_all:7.1f} s  "
        f"peak {m_all / 2**20:7.1f} MiB  (C_eps WTA, normal, non-glass: {wta['value']:.3f})"
    )
    print(f"ratio whole scene / one full-volume seed: {t_all / t_full:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
