"""Benchmark: what the render cache costs against the render it saves.

Runs the workflow's render job (:func:`stereovar.jobs.render.render_job`) twice on one
batch of one scene with the render cache on: the first run renders every seed of both views
and writes each render to the cache; the second, with the batch's stores deleted as a failed
rerun would leave them, reads every render from the cache. It prints both wall times, their
ratio (the named baseline is the first, rendering run), the cache's size against the render
stores' and the per-render cache write time (rendering with the cache on against off).

Usage::

    .venv/bin/python bench/render_cache.py                          # 320x180, SPP 32, 2 seeds
    .venv/bin/python bench/render_cache.py --width 1280 --height 720 --spp 64
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _size(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="scene_000")
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=180)
    parser.add_argument("--spp", type=int, default=32)
    parser.add_argument("--seeds", type=int, default=2)
    args = parser.parse_args(argv)

    import logging

    from stereovar.jobs.render import render_job

    logging.basicConfig(level=logging.WARNING)
    spec = REPO / "scenes" / f"{args.scene}.yaml"
    options = {
        "width": args.width,
        "height": args.height,
        "baseline_m": 0.026,
        "convention": "paper",
        "integrator": "path",
        "max_depth": 8,
        "rfilter": "box",
        "sampler": "independent",
    }
    with tempfile.TemporaryDirectory(prefix="stereovar-cache-") as tmp:
        root = Path(tmp)
        outputs = {v: str(root / f"{v}.zarr") for v in ("left", "right")}
        seeds = list(range(args.seeds))

        def run(cache):
            for path in outputs.values():
                shutil.rmtree(path, ignore_errors=True)
            start = time.perf_counter()
            render_job(spec, outputs, seeds=seeds, spp=args.spp, cache=cache, **options)
            return time.perf_counter() - start

        run(None)  # warm-up: JIT kernels and the texture cache
        plain = run(None)
        rendered = run(root / "cache")
        cached = run(root / "cache")
        stores = sum(_size(Path(p)) for p in outputs.values())
        size = _size(root / "cache")
    n = 2 * args.seeds
    print(
        f"{args.scene} {args.width}x{args.height} SPP {args.spp}, {n} renders: rendering "
        f"{rendered:.2f} s (cache off {plain:.2f} s: writing the cache costs "
        f"{(rendered - plain) / n * 1000:+.0f} ms per render), from the cache {cached:.2f} s; "
        f"ratio cached / rendering {cached / rendered:.3f}; cache {size / 2**20:.1f} MiB "
        f"for {stores / 2**20:.1f} MiB of render stores"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
