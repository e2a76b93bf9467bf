"""A workflow job imports what it computes with: without dask, unless asked for
(``STEREOVAR_DASK``, set to 0 by the Snakefile), reading its stores the same numbers,
whichever stereovar module it imports first."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import xarray as xr

from stereovar.io.store import write_dataset

READ = """
import json, sys
from stereovar.io.contracts import config_digest  # a job's first import (the claims job's)
from stereovar.io.store import load_store
ds = load_store(sys.argv[1], "variance store")
print(json.dumps({"dask": sys.modules.get("dask") is not None,
                  "sum": float(ds["variance"].values.sum()), "first": float(ds["variance"][0, 1])}))
"""


def _read(store, dask_setting):
    env = {k: v for k, v in os.environ.items() if k != "STEREOVAR_DASK"}
    if dask_setting is not None:
        env["STEREOVAR_DASK"] = dask_setting
    out = subprocess.run([sys.executable, "-c", READ, str(store)], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)


def test_a_workflow_job_reads_its_stores_without_dask_and_gets_the_same_numbers(tmp_path):
    values = np.random.default_rng(0).gamma(2.0, 0.1, (6, 9))
    store = tmp_path / "v.zarr"
    coords = {"y": np.arange(6), "x": np.arange(9)}  # as every store has
    write_dataset(xr.Dataset({"variance": (("y", "x"), values)}, coords=coords), store)
    job = _read(store, "0")  # as the Snakefile sets it for its jobs
    free = _read(store, None)
    assert not job["dask"]
    assert free["dask"]  # xarray imports it where it is installed and not refused
    assert job["sum"] == free["sum"] == float(values.sum())
    assert job["first"] == float(values[0, 1])
    assert _read(store, "1")["dask"]  # asked for


def test_reading_the_workflow_imports_no_renderer_network_or_denoiser():
    """Every stereovar module the Snakefile and its rules import, at the top or inside an
    input function, imported together: none pulls in PyTorch, Mitsuba, Dr.Jit, Blender, the
    denoiser, OpenCV or dask (each dry run and each `stereovar run` reads the workflow)."""
    import re
    from pathlib import Path

    repo = Path(__file__).resolve().parents[1]
    modules = set()
    for path in [repo / "Snakefile", *sorted((repo / "workflow").rglob("*.smk"))]:
        text = path.read_text()
        modules |= set(re.findall(r"^\s*from (stereovar[\w.]*) import", text, re.M))
        modules |= set(re.findall(r"^\s*import (stereovar[\w.]*)", text, re.M))
    assert "stereovar.probe.folds" in modules  # an input function's own import is seen
    heavy = ("torch", "mitsuba", "drjit", "bpy", "pyoidn", "cv2", "dask")
    code = "import sys\n" + "".join(f"import {m}\n" for m in sorted(modules)) + (
        f"print(sorted(m for m in {heavy!r} if sys.modules.get(m) is not None))")
    env = {k: v for k, v in os.environ.items() if k != "STEREOVAR_DASK"}  # as a user's shell
    out = subprocess.run([sys.executable, "-c", code], env=env, check=True,
                         capture_output=True, text=True).stdout
    assert json.loads(out.replace("'", '"')) == []
