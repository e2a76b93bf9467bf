"""Benchmark: the ``denoise`` transform's throughput against pyoidn alone on the same arrays.

Times :func:`stereovar.transforms.denoise.apply_denoise` (input checks, finite handling, the
cached OIDN device with ``--threads`` threads) and ``pyoidn.denoise`` (the named baseline:
pyoidn's own convenience call, its default device using every core) on the same noisy
render with albedo and normal passes, in the same run, after one warm-up call each (OIDN
loads its weights on the first commit). It prints ms per megapixel for both and their ratio,
with and without the auxiliary passes, and the transform at pyoidn's thread count for an
equal-threads ratio.

Usage::

    .venv/bin/python bench/denoise.py                       # 640x360, 5 repeats, 1 thread
    .venv/bin/python bench/denoise.py --width 1280 --height 720 --threads 2
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np


def _image(width: int, height: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:height, 0:width]
    clean = np.stack(
        [
            0.5 + 0.4 * np.sin(xx / 23.0),
            0.3 + 0.5 * ((xx // 40 + yy // 40) % 2),
            0.2 + 0.1 * np.cos(yy / 11.0),
        ],
        -1,
    ).astype(np.float32)
    albedo = np.clip(clean, 0, 1)
    normal = np.zeros_like(clean)
    normal[..., 2] = 1.0
    noisy = np.maximum(clean * rng.gamma(4.0, 0.25, clean.shape), 0).astype(np.float32)
    return noisy, albedo, normal


def _best(fn, repeats: int) -> float:
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=360)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args(argv)

    import pyoidn

    from stereovar.transforms import TransformInputs, get_transform

    noisy, albedo, normal = _image(args.width, args.height)
    mpix = args.width * args.height / 1e6
    denoise = get_transform("denoise")
    cores = os.cpu_count() or 1
    print(
        f"denoise {args.width}x{args.height} ({mpix:.2f} MP), best of {args.repeats}, {cores} cores"
    )
    for label, aux in (("albedo+normal", (albedo, normal)), ("colour only", (None, None))):
        inputs = TransformInputs(noisy, "left", 0, 0, albedo=aux[0], normal=aux[1])
        ours = _best(lambda: denoise(inputs, threads=args.threads), args.repeats)  # noqa: B023
        ours_all = _best(lambda: denoise(inputs, threads=cores), args.repeats)  # noqa: B023
        base = _best(
            lambda: pyoidn.denoise(noisy, aux[0], aux[1], hdr=True),  # noqa: B023
            args.repeats,
        )
        print(
            f"  {label}: transform {ours / mpix * 1e3:.0f} ms/MP ({args.threads} thread(s)), "
            f"{ours_all / mpix * 1e3:.0f} ms/MP ({cores} threads); pyoidn.denoise "
            f"{base / mpix * 1e3:.0f} ms/MP (default device); ratio transform / pyoidn "
            f"{ours / base:.2f} ({args.threads} thread(s)), {ours_all / base:.2f} (equal threads)"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
