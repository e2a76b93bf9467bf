"""Benchmark: the CPU time every workflow job pays before it computes anything.

An *empty job* of a kind is what Snakemake's ``script:`` directive runs for it, up to its
first computation: a fresh Python process, Snakemake's preamble (the imports that unpickle
its ``snakemake`` object), the adapter script in ``workflow/scripts/`` with its imports, and
the imports the job function makes as it starts (the ``import`` statements of its body,
read from the source). The job function itself is not called: ``stereovar.jobs.common.run_job``
is replaced by one that makes those imports and returns. The environment is a workflow
job's (``STEREOVAR_DASK=0``, ``OPENBLAS_NUM_THREADS=1``; see ``Snakefile``).

Each kind's CPU time (user + system, the least of ``--repeats`` runs) is printed beside the
named baseline measured in the same run, **the bare preamble**: a Python process that makes
Snakemake's preamble imports and nothing else (the floor any job of the workflow pays),
with the ratio to it and the budget :data:`BUDGET`.

Usage::

    .venv/bin/python bench/job_overhead.py                 # every kind, this checkout
    .venv/bin/python bench/job_overhead.py --repo /path/to/other/checkout   # its scripts
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
import textwrap
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

BUDGET = 0.5
"""CPU seconds an empty job may take."""

PREAMBLE = "import sys, pickle\nfrom snakemake.logging import logger\nimport snakemake.script\n"
"""What Snakemake's Python preamble imports to unpickle the ``snakemake`` object
(``snakemake.script.PythonScript.generate_preamble``)."""

STUB = textwrap.dedent(
    '''
    class _Stub:
        """Stands in for the snakemake object: every attribute, item and call is a stub."""
        def __getattr__(self, name): return _Stub()
        def __getitem__(self, key): return _Stub()
        def __call__(self, *a, **k): return _Stub()
        def __iter__(self): return iter(())
        def __len__(self): return 0
        def __int__(self): return 0
        def __float__(self): return 0.0
        def __index__(self): return 0
        def __bool__(self): return False
        def __str__(self): return "stub"
        def __fspath__(self): return "stub"
        def keys(self): return []
        def items(self): return []
        def get(self, key, default=None): return default
    snakemake = _Stub()
    '''
)

EMPTY_RUN_JOB = textwrap.dedent(
    '''
    import ast, importlib, inspect, textwrap
    import stereovar.jobs.common as _common

    def _body_imports(job):
        """Import what ``job``'s body imports, as it would on its first line."""
        module = inspect.getmodule(job)
        tree = ast.parse(textwrap.dedent(inspect.getsource(job)))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                name = "." * node.level + (node.module or "")
                base = importlib.util.resolve_name(name, module.__package__)
                target = importlib.import_module(base)
                for alias in node.names:
                    if not hasattr(target, alias.name):
                        importlib.import_module(f"{base}.{alias.name}")
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    importlib.import_module(alias.name)

    def _empty_run_job(log_path, job, **kwargs):
        _body_imports(job)

    _common.run_job = _empty_run_job
    '''
)


def kinds(repo: Path) -> list[str]:
    """Every job kind: the adapter scripts of ``workflow/scripts``."""
    return sorted(p.stem for p in (repo / "workflow" / "scripts").glob("*.py"))


def adapter_code(repo: Path, kind: str) -> str:
    """The adapter script of ``kind`` with its ``from stereovar.jobs.common import run_job``
    left to the empty ``run_job`` already installed."""
    source = (repo / "workflow" / "scripts" / f"{kind}.py").read_text()
    tree = ast.parse(source)
    keep = [
        node for node in tree.body
        if not (isinstance(node, ast.ImportFrom) and node.module == "stereovar.jobs.common"
                and [a.name for a in node.names] == ["run_job"])
    ]
    return "from stereovar.jobs.common import run_job\n" + ast.unparse(
        ast.Module(body=keep, type_ignores=[]))


def child_cpu(code: str, repo: Path, repeats: int) -> float:
    """The least user + system CPU time of ``repeats`` fresh processes running ``code``."""
    env = {**os.environ, "STEREOVAR_DASK": "0", "OPENBLAS_NUM_THREADS": "1",
           "PYTHONPATH": str(repo / "src")}
    times = []
    for _ in range(repeats):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([sys.executable, "-c", code], check=True, cwd=repo, env=env,
                       stdout=subprocess.DEVNULL)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        times.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return min(times)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repo", type=Path, default=REPO,
                        help="the checkout whose scripts and package are measured")
    parser.add_argument("--kinds", nargs="*", help="job kinds (default: every script)")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    repo = args.repo.resolve()
    baseline = child_cpu(PREAMBLE, repo, args.repeats)
    print(f"baseline (bare preamble: python + Snakemake's preamble imports): {baseline:.3f} "
          "CPU-s")
    print(f"{'job kind':<28} {'CPU-s':>6} {'x baseline':>10}  budget {BUDGET}")
    results = {}
    for kind in args.kinds or kinds(repo):
        code = PREAMBLE + STUB + EMPTY_RUN_JOB + adapter_code(repo, kind)
        results[kind] = cpu = child_cpu(code, repo, args.repeats)
        flag = "" if cpu <= BUDGET else "  over"
        print(f"{kind:<28} {cpu:6.3f} {cpu / baseline:10.1f}{flag}")
    values = list(results.values())
    print(f"median {statistics.median(values):.3f} CPU-s, largest {max(values):.3f} "
          f"({max(results, key=results.get)}), {sum(v > BUDGET for v in values)} of "
          f"{len(values)} kinds over {BUDGET}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
