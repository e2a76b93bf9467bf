"""Benchmark: what the calibration costs, against the rest of the same run's jobs.

Reads Snakemake's per-job benchmark files of one finished run (``benchmarks/`` of the working
directory after ``make run``, or ``--benchmarks DIR``), or makes a fresh run first
(``--run``: the default config in a temporary copy with an empty render cache, about 25 min
on 2 cores), and sums the job seconds of

* the calibration: ``calibration_scene`` and ``calibration_table`` (it renders nothing);
* the analysis jobs: every job that is not a render (variance, warp, correlation, the
  intervention, the transforms, the mitigation rows, the tables, figures and pages);
* the renders: ``render``, ``render_policy``, ``render_moments``, ``render_aux``.

It prints the calibration's ratio to the analysis jobs (the named baseline) and to the rest
of the run (renders and analysis), whose budget is 0.3 (:data:`BUDGET`).

Usage::

    .venv/bin/python bench/calibration.py                    # after `make run`
    .venv/bin/python bench/calibration.py --benchmarks /path/to/benchmarks
    .venv/bin/python bench/calibration.py --run              # a fresh default run first
"""

from __future__ import annotations

import argparse
import csv
import shutil
import subprocess
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

BUDGET = 0.3
"""The calibration's job time over the rest of the run's (renders and analysis), at most:
it renders nothing, so its draws, transforms and statistics must stay a fraction of what
they calibrate."""

RENDER_PARTS = ("renders",)
"""Benchmark folders of the render jobs (``benchmarks/{source}/renders/...``)."""


def part_of(relative: Path) -> str:
    """``calibration``, ``renders`` or ``analysis`` for a benchmark file's path relative to
    the benchmarks folder."""
    parts = relative.parts
    if "calibration" in parts or relative.stem == "calibration":
        return "calibration"
    if any(p in RENDER_PARTS for p in parts[:-1]):
        return "renders"
    return "analysis"


GENERATOR_PARTS = ("generators", "cycles")
"""Benchmark folders of the ``generators`` target, which ``all`` does not build (read only
with ``--with-generators``)."""


def job_seconds(benchmarks: Path, *, generators: bool = False) -> dict:
    """Seconds and job counts per part (:func:`part_of`), without the ``generators`` target's
    jobs unless ``generators``."""
    totals: dict = defaultdict(lambda: [0.0, 0])
    for tsv in sorted(benchmarks.rglob("*.tsv")):
        if not generators and tsv.relative_to(benchmarks).parts[0] in GENERATOR_PARTS:
            continue
        with tsv.open() as fh:
            row = next(csv.DictReader(fh, delimiter="\t"))
        part = part_of(tsv.relative_to(benchmarks))
        totals[part][0] += float(row["s"])
        totals[part][1] += 1
    return {k: tuple(v) for k, v in totals.items()}


def fresh_run(root: Path) -> Path:
    for name in ("Snakefile", "config.yaml"):
        shutil.copy(REPO / name, root / name)
    for name in ("workflow", "profiles", "envs", "scenes"):
        shutil.copytree(REPO / name, root / name)
    proc = subprocess.run(
        [sys.executable, "-m", "snakemake", "-j2", "all"], cwd=root, capture_output=True,
        text=True,
    )
    if proc.returncode:
        sys.exit(f"snakemake -j2 all failed:\n{proc.stderr[-3000:]}")
    return root / "benchmarks"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--benchmarks", type=Path, default=Path("benchmarks"))
    parser.add_argument("--run", action="store_true", help="make a fresh default run first")
    parser.add_argument("--with-generators", action="store_true",
                        help="count the generators target's jobs too (stereovar run generators)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="stereovar-bench-") as tmp:
        folder = fresh_run(Path(tmp)) if args.run else args.benchmarks
        if not folder.is_dir():
            sys.exit(f"no benchmarks folder {folder}; run `make run` first, or pass --run")
        parts = job_seconds(folder, generators=args.with_generators)
    cal, n_cal = parts.get("calibration", (0.0, 0))
    ana, n_ana = parts.get("analysis", (0.0, 0))
    ren, n_ren = parts.get("renders", (0.0, 0))
    if not n_cal:
        sys.exit(f"no calibration jobs among {folder}; run `snakemake -j2 all` first")
    rest = ana + ren
    print(f"analysis jobs (baseline): {ana:8.1f} s in {n_ana} jobs")
    print(f"render jobs:              {ren:8.1f} s in {n_ren} jobs")
    print(f"calibration:              {cal:8.1f} s in {n_cal} jobs  "
          f"ratio to the analysis jobs {cal / ana:.2f}")
    print(f"the calibration over the rest of the run's job time: {cal / rest:.2f} "
          f"(budget {BUDGET:.2f}); the run's job time with it over without it "
          f"{(rest + cal) / rest:.2f}")


if __name__ == "__main__":
    main()
