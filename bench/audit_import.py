"""Audit import cost against reading the same EXR files with the OpenEXR library alone.

Writes N seeds x 2 views of one 1280x720 frame as float32 ZIP-compressed EXR (synthetic
renders, :mod:`stereovar.audit.synthetic`) with a PFM disparity, then, each in a fresh
process (cold Python, warm page cache):

* read: every EXR decoded once with ``OpenEXR.File`` (the baseline);
* import: :func:`stereovar.audit.importer.import_audit` into empty results: discovery,
  headers, SHA-256 of every file, decoding, the sign check and the atomic store writes;
* reimport: the same import again (nothing changed: hashes only, nothing written).

It prints import / read (goal <= 1.5) and reimport / read. With ``--workflow`` it also runs
the whole audit (``snakemake -j2 all`` with the audit config: every statistic, control, the
intervention and the verdict page) in a copy of the workflow and prints its wall-clock time
(goal < 2 minutes on 2 cores).

Usage::

    .venv/bin/python bench/audit_import.py              # N = 30, 1280x720
    .venv/bin/python bench/audit_import.py --workflow
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]

# Both timings start once the libraries are imported; xarray imports dask lazily on its
# first Dataset, so the import snippet imports it first, as the read snippet imports OpenEXR.
# The cold-process wall times, imports included, are printed as well.
READ = """
import glob, sys, time, OpenEXR
t = time.perf_counter()
for p in sorted(glob.glob(sys.argv[1] + "/renders/*/*/*.exr")):
    with OpenEXR.File(p, separate_channels=True) as f:
        [c.pixels for c in f.channels().values()]
print(time.perf_counter() - t)
"""

IMPORT = """
import os, sys, time, yaml
os.chdir(sys.argv[1])
import dask.array
from stereovar.audit.importer import import_audit
settings = yaml.safe_load(open("audit.yaml"))["audit"]
t = time.perf_counter()
report = import_audit(settings)
total = time.perf_counter() - t
print(report.lines()[0], file=sys.stderr)
print("  " + ", ".join(f"{k} {v:.2f} s" for k, v in report.seconds.items()), file=sys.stderr)
print(total)
"""


def timed(code: str, *args) -> tuple[float, float]:
    """(time inside the process after its imports, wall time of the whole process)."""
    t = time.perf_counter()
    out = subprocess.run(
        [sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True, check=True
    )
    wall = time.perf_counter() - t
    print(out.stderr.strip(), file=sys.stderr) if out.stderr.strip() else None
    return float(out.stdout.strip().splitlines()[-1]), wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=30)
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--height", type=int, default=720)
    parser.add_argument("--workflow", action="store_true", help="also time the whole audit")
    args = parser.parse_args()
    from stereovar.audit.synthetic import write_synthetic_audit

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        settings, _ = write_synthetic_audit(
            tmp / "data",
            name="bench",
            n_frames=1,
            n_seeds=args.seeds,
            width=args.width,
            height=args.height,
            block=32,
        )
        (tmp / "audit.yaml").write_text(yaml.safe_dump({"audit": settings}))
        os.sync()  # neither timing pays for writing back the files just generated
        n_files = 2 * args.seeds
        print(f"{n_files} EXR files of {args.width}x{args.height} (float32, ZIP)")
        (read, read_cold), _ = sorted(timed(READ, tmp / "data") for _ in range(2))
        imp, imp_cold = timed(IMPORT, tmp)
        again, _ = timed(IMPORT, tmp)
        print(f"read (OpenEXR alone, baseline): {read:.2f} s")
        print(f"import: {imp:.2f} s  ->  import / read = {imp / read:.2f} (goal <= 1.5)")
        print(
            f"cold processes, imports included: import {imp_cold:.2f} s / read "
            f"{read_cold:.2f} s = {imp_cold / read_cold:.2f}"
        )
        print(f"reimport (nothing changed): {again:.2f} s  ->  {again / read:.2f} x read")
        if args.workflow:
            work = tmp / "wf"
            work.mkdir()
            for name in ("Snakefile", "config.yaml"):
                shutil.copy(REPO / name, work / name)
            for name in ("workflow", "profiles", "envs"):
                shutil.copytree(REPO / name, work / name)
            shutil.copy(tmp / "audit.yaml", work / "audit.yaml")
            t = time.perf_counter()
            subprocess.run(
                [sys.executable, "-m", "snakemake", "-j2", "all", "--configfile", "audit.yaml"],
                cwd=work,
                check=True,
                capture_output=True,
            )
            total = time.perf_counter() - t
            print(f"whole audit (import, every statistic and control, intervention, verdict): "
                  f"{total:.0f} s (goal < 120 s)")


if __name__ == "__main__":
    main()
