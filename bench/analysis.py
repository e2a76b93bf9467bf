"""Analysis cost at paper scale: every statistic and control against Eq. 1-3 alone.

Writes N left and N right synthetic render stores at 1280x720 (float32 radiance, the same
store layout and compression as the workflow's) and a ground truth, then, each in a fresh
process so peak RSS is its own:

* read: every render store read once (``open_dataset(...)["radiance"].values``);
* Eq. 1-3: the variance fields (no seed subsets), the warp and Pearson's rho with its
  Fisher-z interval for ``warp`` and ``no_warp`` in each region: the paper's analysis;
* full: the workflow's variance, warp and correlation jobs: every registered statistic and
  control with block-bootstrap intervals (1000 replicates), split-half reliability, the
  seed-subset curve and the sensor baseline.

It prints full / Eq. 1-3 in wall-clock (goal <= 1.5) and CPU time (the cost when scenes
run as parallel jobs), full / read, each job's wall-clock time, and the peak RSS for N and N/3 seeds
(goal < 1.5 GB and not growing with N).

With ``--moments`` the inputs are one moment store per view (two half renders at SPP 64,
:mod:`stereovar.io.moments`) and both the Eq. 1-3 baseline and the full analysis use the
``moments`` estimator: no seed subsets to build, store or correlate.

Usage::

    .venv/bin/python bench/analysis.py            # N = 30, 1280x720
    .venv/bin/python bench/analysis.py --seeds 10 --width 640 --height 360
    .venv/bin/python bench/analysis.py --moments
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import xarray as xr

READ = r"""
import json, resource, sys, time
from stereovar.io.store import open_dataset
paths = json.loads(sys.argv[1])
start, cpu0 = time.perf_counter(), time.process_time()
total = 0.0
for p in paths:
    total += float(open_dataset(p)["radiance"].values[0, 0, 0])
seconds, cpu = time.perf_counter() - start, time.process_time() - cpu0
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"seconds": seconds, "cpu": cpu, "rss_mb": rss}))
"""

EQ123 = r"""
import json, resource, sys, time
import stereovar.io.store  # xarray and zarr, imported before the clock as in the baseline
from stereovar.estimators.seeds import variance_dataset
from stereovar.io.store import open_dataset
from stereovar.statistics.correlation import pearson_over_mask
from stereovar.statistics.regions import region_masks
from stereovar.statistics.warp import align_variance
args = json.loads(sys.argv[1])
start, cpu0 = time.perf_counter(), time.process_time()
if args.get("moments"):
    from stereovar.estimators.moments import moment_variance_dataset
    v = moment_variance_dataset(args["left"], args["right"])
else:
    v = variance_dataset(args["left"], args["right"], subsets=False)
gt = open_dataset(args["gt"]).sel(view="left").load()
left, right = (v["variance"].sel(view=k).values for k in ("left", "right"))
aligned = align_variance(left, right, gt, sign=1)
for mask in region_masks(gt, aligned["omega"]).values():
    pearson_over_mask(left, aligned["warped"], mask)
    pearson_over_mask(left, right, mask)
seconds, cpu = time.perf_counter() - start, time.process_time() - cpu0
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"seconds": seconds, "cpu": cpu, "rss_mb": rss}))
"""

ANALYSE = r"""
import json, resource, sys, time
import stereovar.io.store  # xarray and zarr, imported before the clock as in the baseline
import stereovar.statistics.rows, scipy.stats  # imported before the clock, as in Eq. 1-3
from stereovar.jobs.correlation import correlation_job, warp_job
from stereovar.jobs.variance import variance_job
args = json.loads(sys.argv[1])
start, cpu0 = time.perf_counter(), time.process_time()
variance_job(args["left"], args["right"], args["work"] + "/var.zarr",
             estimator="moments" if args.get("moments") else "seeds")
stages = {"variance": time.perf_counter() - start}
warp_job(args["work"] + "/var.zarr", args["gt"], args["work"] + "/warp.zarr")
stages["warp"] = time.perf_counter() - start - stages["variance"]
correlation_job(args["work"] + "/var.zarr", args["work"] + "/warp.zarr", args["gt"],
                args["work"] + "/corr.csv", curve=args["work"] + "/curve.csv")
seconds, cpu = time.perf_counter() - start, time.process_time() - cpu0
stages["correlation"] = seconds - stages["variance"] - stages["warp"]
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"seconds": seconds, "cpu": cpu, "rss_mb": rss, "stages": stages}))
"""


def write_inputs(root: Path, n: int, width: int, height: int) -> dict:
    from stereovar.io.store import write_dataset

    rng = np.random.default_rng(0)
    yy, xx = np.mgrid[0:height, 0:width]
    amp = (0.05 + 0.05 * np.sin(xx / 17.0) ** 2 + 0.05 * yy / height).astype(np.float32)
    paths = {"left": [], "right": []}
    for view in ("left", "right"):
        for k in range(n):
            img = 0.3 + amp[..., None] * rng.standard_normal((height, width, 3), np.float32)
            da = xr.DataArray(
                img,
                dims=("y", "x", "channel"),
                coords={"channel": ["R", "G", "B"]},
                name="radiance",
                attrs={"scene": "bench", "spp": 512, "view": view, "seed_index": k},
            )
            path = root / f"{view}_seed{k}.zarr"
            write_dataset(da, path)
            paths[view].append(str(path))
    glass = np.zeros((2, height, width), bool)
    glass[:, height // 4 : height // 2, width // 4 : width // 2] = True
    gt = xr.Dataset(
        {
            "disparity": (
                ("view", "y", "x"),
                np.broadcast_to(4.0 + 8.0 * yy / height, (2, height, width)).astype(np.float32),
            ),
            "valid": (("view", "y", "x"), np.ones((2, height, width), bool)),
            "glass": (("view", "y", "x"), glass),
        },
        coords={"view": ["left", "right"]},
        attrs={"disparity_sign": 1, "convention": "paper"},
    )
    write_dataset(gt, root / "gt.zarr")
    return {"left": paths["left"], "right": paths["right"], "gt": str(root / "gt.zarr")}


def write_moment_inputs(root: Path, width: int, height: int, spp: int = 64) -> dict:
    """One moment store per view (two halves of ``spp / 2`` samples) whose per-sample
    variance follows the same amplitude pattern as :func:`write_inputs`' renders, drawn
    from the sampling laws of the mean and the sample variance of Gaussian samples."""
    from stereovar.io.moments import moments_dataset
    from stereovar.io.store import write_dataset
    from stereovar.renderers.base import SampleMoments

    rng = np.random.default_rng(0)
    yy, xx = np.mgrid[0:height, 0:width]
    amp = (0.05 + 0.05 * np.sin(xx / 17.0) ** 2 + 0.05 * yy / height)[..., None] * np.sqrt(spp)
    n = spp // 2
    paths = {}
    for view in ("left", "right"):
        halves = []
        for _ in range(2):
            mean = 0.3 + amp * rng.standard_normal((height, width, 3)) / np.sqrt(n)
            s2 = amp**2 * rng.chisquare(n - 1, (height, width, 3)) / (n - 1)
            halves.append(
                SampleMoments(
                    mean.astype(np.float32),
                    (mean**2 + s2 * (n - 1) / n).astype(np.float32),
                    np.full((height, width), n, np.int32),
                )
            )
        ds = moments_dataset(
            halves,
            view=view,
            sampler_seeds=[1, 2],
            half_spp=[n, n],
            attrs={"scene": "bench", "spp": spp},
        )
        paths[view] = [str(write_dataset(ds, root / f"{view}_moments.zarr"))]
    inputs = write_inputs(root, 0, width, height)
    return {**paths, "gt": inputs["gt"]}


def run(code: str, arg) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", code, json.dumps(arg)], capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=30)
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--height", type=int, default=720)
    parser.add_argument("--moments", action="store_true", help="the moments estimator")
    args = parser.parse_args(argv)
    if args.moments:
        return main_moments(args)

    with tempfile.TemporaryDirectory(prefix="stereovar-bench-") as tmp:
        root = Path(tmp)
        inputs = write_inputs(root, args.seeds, args.width, args.height)
        results = {}
        for n in sorted({max(2, args.seeds // 3), args.seeds}):
            work = root / f"n{n}"
            work.mkdir()
            subset = {
                **inputs,
                "left": inputs["left"][:n],
                "right": inputs["right"][:n],
                "work": str(work),
            }
            read = run(READ, subset["left"] + subset["right"])
            eq123 = run(EQ123, subset)
            analysis = run(ANALYSE, subset)
            results[n] = (read, analysis)
            print(
                f"N={n}, {args.width}x{args.height}: read {read['seconds']:.2f} s; "
                f"Eq. 1-3 {eq123['seconds']:.2f} s; all statistics and controls "
                f"{analysis['seconds']:.2f} s; ratio to Eq. 1-3 "
                f"{analysis['seconds'] / eq123['seconds']:.2f} (goal <= 1.5); CPU time "
                f"{analysis['cpu']:.2f} s against {eq123['cpu']:.2f} s, ratio "
                f"{analysis['cpu'] / eq123['cpu']:.2f}; ratio to read "
                f"{analysis['seconds'] / read['seconds']:.2f}; peak RSS "
                f"{analysis['rss_mb']:.0f} MB (Eq. 1-3 {eq123['rss_mb']:.0f} MB, read alone "
                f"{read['rss_mb']:.0f} MB)\n  jobs: "
                + ", ".join(f"{k} {v:.2f} s" for k, v in analysis["stages"].items())
            )
    small, large = min(results), max(results)
    growth = results[large][1]["rss_mb"] / results[small][1]["rss_mb"]
    print(f"peak RSS N={large} / N={small}: {growth:.2f} (goal: flat, < 1.5 GB)")
    return 0


def main_moments(args) -> int:
    """Full analysis against Eq. 1-3, both with the moments estimator."""
    with tempfile.TemporaryDirectory(prefix="stereovar-bench-") as tmp:
        root = Path(tmp)
        inputs = {**write_moment_inputs(root, args.width, args.height), "moments": True}
        inputs["work"] = str(root)
        read = run(READ_MOMENTS, inputs["left"] + inputs["right"])
        eq123 = run(EQ123, inputs)
        analysis = run(ANALYSE, inputs)
    print(
        f"moments, {args.width}x{args.height}, SPP 64: read {read['seconds']:.2f} s; Eq. 1-3 "
        f"{eq123['seconds']:.2f} s; all statistics and controls {analysis['seconds']:.2f} s; "
        f"ratio to Eq. 1-3 {analysis['seconds'] / eq123['seconds']:.2f} (goal <= 1.5); CPU "
        f"time {analysis['cpu']:.2f} s against {eq123['cpu']:.2f} s, ratio "
        f"{analysis['cpu'] / eq123['cpu']:.2f}; peak RSS {analysis['rss_mb']:.0f} MB (Eq. 1-3 "
        f"{eq123['rss_mb']:.0f} MB)\n  jobs: "
        + ", ".join(f"{k} {v:.2f} s" for k, v in analysis["stages"].items())
    )
    return 0


READ_MOMENTS = READ.replace('["radiance"].values[0, 0, 0]', '["sample_mean_sq"].values[0, 0, 0, 0]')


if __name__ == "__main__":
    sys.exit(main())
