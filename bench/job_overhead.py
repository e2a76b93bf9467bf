"""Benchmark: the CPU time every workflow job pays before it computes anything.

An *empty job* of a kind is what Snakemake's ``script:`` directive runs for it, up to its
first computation: a fresh Python process, Snakemake's preamble (the imports that unpickle
its ``snakemake`` object), the adapter script in ``workflow/scripts/`` with its imports, and
the imports the job function makes as it starts (the ``import`` statements of its body,
read from the source), and, for a kind that reads stores (its imports hold xarray), reading
one small store (:func:`stereovar.io.store.load_store`: 180x320 float32 with its
coordinates). Neither the adapter's ``run_job`` call nor the job function runs. The
environment is a workflow job's (``STEREOVAR_DASK=0``, ``OPENBLAS_NUM_THREADS=1``; see
``Snakefile``).

Each kind's CPU time (user + system, the least of ``--repeats`` runs) is printed beside the
named baseline measured in the same run, **the bare preamble**: a Python process that makes
Snakemake's preamble imports and nothing else (the floor any job of the workflow pays),
with the ratio to it and the budget :data:`BUDGET`.

Usage::

    .venv/bin/python bench/job_overhead.py                 # every kind, this checkout
    .venv/bin/python bench/job_overhead.py --against /tmp/before   # beside an older checkout
    .venv/bin/python bench/job_overhead.py --kinds warp correlation --repeats 7
"""

from __future__ import annotations

import argparse
import ast
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

BUDGET = 0.5
"""CPU seconds an empty job may take."""

PREAMBLE = "import sys, pickle\nfrom snakemake.logging import logger\nimport snakemake.script\n"
"""What Snakemake's Python preamble imports to unpickle the ``snakemake`` object
(``snakemake.script.PythonScript.generate_preamble``)."""

BODY_IMPORTS = textwrap.dedent(
    '''
    import ast, importlib, inspect, textwrap

    def _body_imports(job):
        """Import what ``job``'s body imports, as it does on its first lines."""
        module = inspect.getmodule(job)
        tree = ast.parse(textwrap.dedent(inspect.getsource(job)))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                base = importlib.util.resolve_name("." * node.level + (node.module or ""),
                                                   module.__package__)
                target = importlib.import_module(base)
                for alias in node.names:
                    if not hasattr(target, alias.name):
                        importlib.import_module(f"{base}.{alias.name}")
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    importlib.import_module(alias.name)
    '''
)


def kinds(repo: Path) -> list[str]:
    """Every job kind: the adapter scripts of ``workflow/scripts``."""
    return sorted(p.stem for p in (repo / "workflow" / "scripts").glob("*.py"))


def adapter_code(repo: Path, kind: str) -> str:
    """The imports of ``kind``'s adapter script, then those of the job function it passes
    to ``run_job`` (its second argument), without calling either."""
    tree = ast.parse((repo / "workflow" / "scripts" / f"{kind}.py").read_text())
    imports = [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))]
    calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call)
             and getattr(n.func, "id", None) == "run_job"]
    if len(calls) != 1 or len(calls[0].args) < 2:
        raise SystemExit(f"workflow/scripts/{kind}.py: no single run_job(log, job, ...) call")
    job = ast.unparse(calls[0].args[1])
    return (ast.unparse(ast.Module(body=imports, type_ignores=[])) + f"\n_body_imports({job})\n"
            + READ_STORE)


READ_STORE = """
if "xarray" in sys.modules:
    from stereovar.io.store import load_store
    load_store(sys.argv[1], "store")
"""


def small_store(folder: Path) -> Path:
    """A variance-store-like Zarr store (180x320 float32, coordinates y and x)."""
    import numpy as np
    import xarray as xr

    path = folder / "small.zarr"
    values = np.random.default_rng(0).gamma(2.0, 0.1, (180, 320)).astype(np.float32)
    coords = {"y": np.arange(180), "x": np.arange(320)}
    xr.Dataset({"variance": (("y", "x"), values)}, coords=coords).to_zarr(
        path, mode="w", zarr_format=2, consolidated=True)
    return path


def child_cpu(code: str, repo: Path, repeats: int, *args) -> float:
    """The least user + system CPU time of ``repeats`` fresh processes running ``code``
    (with ``args`` in ``sys.argv[1:]``)."""
    env = {**os.environ, "STEREOVAR_DASK": "0", "OPENBLAS_NUM_THREADS": "1",
           "PYTHONPATH": str(repo / "src")}
    times = []
    for _ in range(repeats):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([sys.executable, "-c", code, *map(str, args)], check=True, cwd=repo,
                       env=env,
                       stdout=subprocess.DEVNULL)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        times.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return min(times)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repo", type=Path, default=REPO,
                        help="the checkout whose scripts and package are measured")
    parser.add_argument("--against", type=Path,
                        help="another checkout (e.g. an earlier commit's), measured beside "
                             "each kind in the same run")
    parser.add_argument("--kinds", nargs="*", help="job kinds (default: every script)")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    repo = args.repo.resolve()
    other = args.against.resolve() if args.against else None
    store = small_store(Path(tempfile.mkdtemp()))
    baseline = child_cpu(PREAMBLE, repo, args.repeats)
    print(f"baseline (bare preamble: python + Snakemake's preamble imports): {baseline:.3f} "
          "CPU-s")
    head = f"{'job kind':<28} {'CPU-s':>6} {'x baseline':>10}"
    print(head + (f" {'against':>8} {'ratio':>6}" if other else "") + f"  budget {BUDGET}")
    results, before = {}, {}
    for kind in args.kinds or kinds(repo):
        results[kind] = cpu = child_cpu(PREAMBLE + BODY_IMPORTS + adapter_code(repo, kind),
                                        repo, args.repeats, store)
        line = f"{kind:<28} {cpu:6.3f} {cpu / baseline:10.1f}"
        if other and (other / "workflow" / "scripts" / f"{kind}.py").exists():
            before[kind] = was = child_cpu(
                PREAMBLE + BODY_IMPORTS + adapter_code(other, kind), other, args.repeats, store)
            line += f" {was:8.3f} {cpu / was:6.2f}"
        print(line + ("" if cpu <= BUDGET else "  over"))
    values = list(results.values())
    print(f"median {statistics.median(values):.3f} CPU-s, largest {max(values):.3f} "
          f"({max(results, key=results.get)}), {sum(v > BUDGET for v in values)} of "
          f"{len(values)} kinds over {BUDGET}")
    if before:
        print(f"against {other}: median {statistics.median(before.values()):.3f} CPU-s, "
              f"largest {max(before.values()):.3f}; the sum over the kinds "
              f"{sum(results[k] for k in before) / sum(before.values()):.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
