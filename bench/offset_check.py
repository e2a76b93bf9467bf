"""Benchmark: how the offset check (:mod:`stereovar.audit.offset`) calibrates, and what it costs
against the sign check measured in the same run.

On frames whose disparity is known it counts how often the check fires with the right
disparity (false alarms), with the disparity declared 2 px too large or too small, and with
the disparity replaced by its mean, and how far the estimated offset lies from the planted
one. The frames:

* flat: noise alone (5% of a grey level of 0.5), 150 frames of each size from 16x24 to
  64x96 px, declared with a constant disparity of 5 px;
* smooth: a sum of 12 sinusoids (up to ``fmax`` cycles/px) seen through a slanted plane with
  a fractional disparity of 4-12 px, so the warp interpolates, with Gaussian noise in the
  seed means (0.5-10% of the signal); 40 frames per setting (two sizes);
* block: :func:`stereovar.audit.synthetic.synthetic_frame` (block texture, an integer
  disparity per row, noisy renders), 20 seeds per setting.

It ends with the time of both checks on one 1280x720 block frame and their ratio (the sign
check is the baseline). About 15 s on 2 cores.

Usage::

    .venv/bin/python bench/offset_check.py
"""

from __future__ import annotations

import time

import numpy as np

from stereovar.audit.offset import MIN_TILES, TEXTURE, offset_check
from stereovar.audit.sign import sign_check
from stereovar.audit.synthetic import slanted_texture_means as smooth_frame
from stereovar.audit.synthetic import synthetic_frame

SIGN = -1


def main() -> None:
    rows: dict[str, list] = {}

    def run(name, left, right, d, planted=None):
        check = offset_check(left, right, d, sign=SIGN)
        errors = np.asarray(check.errors)
        at = check.shifts.index(0)
        ratio = np.delete(errors, at).min() / errors[at]
        rows.setdefault(name, []).append((
            check.fires,
            check.share if check.n_tiles >= MIN_TILES else np.nan,
            ratio if errors.max() >= TEXTURE * errors.min() else np.nan,
            np.nan if planted is None else abs(check.offset - planted),
        ))

    for height, width in [(16, 24), (24, 40), (32, 48), (40, 64), (64, 96)]:
        for seed in range(150):
            noisy = 0.5 + 0.05 * np.random.default_rng(seed).standard_normal((2, height, width, 1))
            run(f"flat {height}x{width} right", *noisy, np.full((height, width), 5.0))
    for noise in (0.005, 0.02, 0.05, 0.1):
        for fmax in (0.1, 0.25, 0.45):
            for seed in range(20):
                for height, width in [(40, 64), (64, 96)]:
                    left, right, d = smooth_frame(
                        seed, noise=noise, fmax=fmax, width=width, height=height
                    )
                    key = f"smooth noise {noise} fmax {fmax}"
                    run(f"{key} right", left, right, d)
                    run(f"{key} d+2", left, right, d + 2, 2.0)
                    run(f"{key} d-2", left, right, d - 2, -2.0)
                    run(f"{key} mean", left, right, np.full_like(d, d.mean()))
    for options in [dict(width=64, height=40, n_seeds=4), {}, dict(level=0.02),
                    dict(level=0.1), dict(n_seeds=4, level=0.1)]:
        for seed in range(20):
            frame = synthetic_frame(sign=SIGN, seed=seed, **options)
            left, right = (frame.renders[v].mean(0, dtype=np.float64) for v in ("left", "right"))
            d = frame.disparity.astype(np.float64)
            key = f"block {options}"
            run(f"{key} right", left, right, d)
            run(f"{key} d+2", left, right, d + 2, 2.0)
            run(f"{key} d-2", left, right, np.where(d > 2, d - 2, np.nan), -2.0)
            run(f"{key} mean", left, right, np.full_like(d, d[frame.valid].mean()))
    alarms = frames = 0
    shares, ratios = [], []
    for name, found in rows.items():
        fired = sum(f[0] for f in found)
        line = f"{name:52s} fired {fired:3d} of {len(found):3d}"
        if name.endswith("right"):
            alarms, frames = alarms + fired, frames + len(found)
            shares += [f[1] for f in found]
            ratios += [f[2] for f in found]
        elif np.isfinite(found[0][3]):
            off = [f[3] for f in found if f[0]]
            line += f"   |offset - planted| at most {max(off):.2f} px" if off else ""
        print(line)
    print(
        f"right disparity: {alarms} false alarms of {frames} frames; largest tile share "
        f"{np.nanmax(shares):.3f}; smallest shifted/declared frame error {np.nanmin(ratios):.3f}"
    )
    frame = synthetic_frame(sign=SIGN, width=1280, height=720, n_seeds=2)
    left, right = (frame.renders[v].mean(0, dtype=np.float64) for v in ("left", "right"))
    seconds = {}
    for check in (sign_check, offset_check) * 2:
        start = time.perf_counter()
        check(left, right, frame.disparity, sign=SIGN, valid=frame.valid)
        seconds[check.__name__] = time.perf_counter() - start
    offset, sign = seconds["offset_check"], seconds["sign_check"]
    print(
        f"1280x720: offset check {offset:.2f} s, sign check (baseline) {sign:.2f} s, "
        f"ratio {offset / sign:.2f}"
    )


if __name__ == "__main__":
    main()
