"""Benchmark: what the mitigation target adds to a run, against the main run, in one run.

Copies the workflow with the default config (``config.yaml``, or ``--configfile`` on top of
it) into a temporary directory with an empty render cache, then runs

1. the main run: ``snakemake -j2 all`` with ``mitigations.names: []`` (the named baseline);
2. ``snakemake -j2 mitigations`` on top of it with the configured mitigations: only what
   the mitigations add (their renders, transforms, analyses, reference and table);

and prints both wall times, their ratio (the issue's budget: at most 1.0, i.e. ``all`` with
the mitigations at most doubles the main run) and what each part of the mitigations costs,
from Snakemake's per-job benchmark files summed per rule and source key.

Usage::

    .venv/bin/python bench/mitigations.py                 # the default config (about 13 min)
    .venv/bin/python bench/mitigations.py --configfile tests/fixtures/tiny/tiny.yaml
"""

from __future__ import annotations

import argparse
import csv
import shutil
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]


def copy_workflow(root: Path) -> None:
    for name in ("Snakefile", "config.yaml"):
        shutil.copy(REPO / name, root / name)
    for name in ("workflow", "profiles", "envs", "scenes"):
        shutil.copytree(REPO / name, root / name)


def run(root: Path, *args: str) -> float:
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "snakemake", "-j2", *args],
        cwd=root,
        capture_output=True,
        text=True,
    )
    elapsed = time.perf_counter() - start
    if proc.returncode:
        sys.exit(f"snakemake {' '.join(args)} failed:\n{proc.stderr[-3000:]}")
    return elapsed


def job_seconds(root: Path, since: float) -> dict:
    """Seconds of every job whose benchmark file was written after ``since``, summed per
    (rule directory, source key)."""
    totals = defaultdict(float)
    for tsv in (root / "benchmarks").rglob("*.tsv"):
        if tsv.stat().st_mtime < since:
            continue
        with tsv.open() as fh:
            row = next(csv.DictReader(fh, delimiter="\t"))
        parts = tsv.relative_to(root / "benchmarks").parts
        key = "/".join(
            p for p in parts[:-1] if not p.startswith(("scene_", "spp", "left", "right"))
        )
        totals[key] += float(row["s"])
    return dict(totals)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--configfile", type=Path, help="a config merged on config.yaml")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="stereovar-bench-") as tmp:
        root = Path(tmp)
        copy_workflow(root)
        extra = []
        if args.configfile:
            shutil.copy(args.configfile, root / "extra.yaml")
            extra = ["--configfile", "extra.yaml"]
        (root / "main.yaml").write_text(yaml.safe_dump({"mitigations": {"names": []}}))
        main_s = (
            run(root, "all", *extra, "--configfile", "main.yaml")
            if extra
            else run(root, "all", "--configfile", "main.yaml")
        )
        marker = time.time()
        mit_s = run(root, "mitigations", *extra)
        parts = job_seconds(root, marker)
    print(f"main run (all, no mitigations):   {main_s:8.1f} s  (baseline)")
    print(f"mitigations target on top of it:  {mit_s:8.1f} s  ratio {mit_s / main_s:.2f}")
    print(
        f"all with the mitigations:         {main_s + mit_s:8.1f} s  "
        f"ratio {(main_s + mit_s) / main_s:.2f} (budget 2.00)"
    )
    print("job seconds of the mitigations, per rule and source key:")
    for key, seconds in sorted(parts.items(), key=lambda kv: -kv[1]):
        print(f"  {seconds:8.1f} s  {key}")


if __name__ == "__main__":
    main()
