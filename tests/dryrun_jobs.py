"""Every job a dry run plans, as sorted text: what the workflow's wiring decides, job by job.

Run as a script in a workflow folder with no outputs yet::

    python tests/dryrun_jobs.py [--configfile extra.yaml ...] TARGET ...

or, to write the listings of :data:`LISTINGS` (each in a fresh copy of this checkout's
workflow with the default ``config.yaml``) into a folder, as ``tests/golden/dryrun`` holds them::

    python tests/dryrun_jobs.py --write DIR [NAME ...]

It prints one JSON line per job of the DAG, sorted: the rule, its wildcards, input, output and
log files, params, threads and numeric resources (``attempt`` 1), benchmark, group, conda
environment and message. Two workflows that print the same lines for a target plan the same
jobs with the same files, settings and requests; the order in which Snakemake would run them
(which may follow dict order) is left out. A folder without outputs makes every job one to run,
so the listing does not depend on what an earlier run left behind.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]
#: The user targets, each a listing of the same name; ``audit`` is ``all`` on the synthetic
#: example's audit (what ``stereovar init --example`` writes, then ``stereovar audit
#: audit.yaml``).
LISTINGS = {
    "all": ["all"],
    "mitigations": ["mitigations"],
    "probe": ["probe"],
    "calibration": ["calibration"],
    "generators": ["generators"],
    "export": ["export"],
    "audit": ["all"],
}
#: The audit's config file in its folder.
AUDIT_CONFIG = "audit.yaml"
#: Resources whose value depends on the machine (a temporary folder, a scheduler's default).
MACHINE_RESOURCES = {"tmpdir", "_cores", "_nodes"}
#: An object's address in a repr: never the same twice.
ADDRESS = re.compile(r" at 0x[0-9a-f]+")


def plain(value):
    """A JSON-ready copy of a job's value: lists stay lists, mappings are sorted, anything
    else is its repr without memory addresses."""
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in sorted(value.items(), key=lambda kv: str(kv[0]))}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    return ADDRESS.sub("", repr(value))


def without_file_status(value):
    """An audit import's ``fingerprint`` param (JSON: a token per file of the file's size,
    time stamps and inode, :func:`stereovar.audit.importer.frame_fingerprint`) with each
    token cut to the size: the time stamps and inode are new with every copy of the files.
    Any other value is returned as it is."""
    if not (isinstance(value, str) and value.startswith('{"files"')):
        return value
    data = json.loads(value)
    data["files"] = {path: token[0] for path, token in data["files"].items()}
    return json.dumps(data, sort_keys=True)


def named(items) -> dict | list:
    """A Snakemake named list (input, params) as {name: value}, plus its unnamed values."""
    names = dict(items._allitems()) if hasattr(items, "_allitems") else {}
    keyed = {k: plain(without_file_status(v)) for k, v in names.items() if k is not None}
    return {
        "named": dict(sorted(keyed.items())),
        "all": [plain(without_file_status(v)) for v in items],
    }


def job_line(job) -> str:
    """One job as a JSON line with sorted keys."""
    resources = {
        k: v
        for k, v in dict(job.resources).items()
        if k not in MACHINE_RESOURCES and isinstance(v, (int, float, str))
    }
    record = {
        "rule": job.rule.name,
        "wildcards": plain(dict(job.wildcards_dict)),
        "output": [str(f) for f in job.output],
        "input": named(job.input),
        "log": [str(f) for f in job.log],
        "params": named(job.params),
        "threads": job.threads,
        "resources": plain(resources),
        "benchmark": str(job.benchmark) if job.benchmark else None,
        "group": job.group,
        "conda": job.rule.conda_env if isinstance(job.rule.conda_env, str) else None,
        "message": job.message,
        "localrule": job.rule.name in job.dag.workflow._localrules,
    }
    return json.dumps(record, sort_keys=True)


def job_lines(targets, configfiles=(), cores: int = 2) -> list[str]:
    """The sorted job lines of a dry run of ``targets`` in the current folder."""
    from snakemake.api import SnakemakeApi
    from snakemake.settings.types import (
        ConfigSettings,
        DAGSettings,
        OutputSettings,
        Quietness,
        ResourceSettings,
    )

    with SnakemakeApi(OutputSettings(quiet={Quietness.ALL})) as api:
        workflow = api.workflow(
            resource_settings=ResourceSettings(cores=cores),
            config_settings=ConfigSettings(configfiles=[Path(f) for f in configfiles]),
            snakefile=Path("Snakefile"),
            workdir=Path("."),
        )
        dag = workflow.dag(dag_settings=DAGSettings(targets=set(targets)))
        dag.execute_workflow(executor="dryrun")
        jobs = workflow._workflow.dag.jobs
        return sorted(job_line(job) for job in jobs)


def workflow_folder(root: Path) -> Path:
    """A copy of this checkout's workflow, default config and scene specs in ``root``."""
    root.mkdir(parents=True, exist_ok=True)
    for name in ("Snakefile", "config.yaml"):
        shutil.copy(REPO / name, root / name)
    for name in ("workflow", "profiles", "envs", "scenes"):
        shutil.copytree(REPO / name, root / name, ignore=shutil.ignore_patterns("__pycache__"))
    return root


def audit_folder(root: Path) -> Path:
    """:func:`workflow_folder` plus the synthetic example's files (``data/synthetic``) and
    an ``audit.yaml`` that audits them."""
    from stereovar.audit.synthetic import write_synthetic_audit

    workflow_folder(root)
    here = Path.cwd()
    os.chdir(root)
    try:
        settings, _ = write_synthetic_audit("data/synthetic")
    finally:
        os.chdir(here)
    (root / AUDIT_CONFIG).write_text(yaml.safe_dump({"audit": settings}))
    return root


def listings(root: Path, names) -> dict[str, list[str]]:
    """The job lines of each listing in ``names``, each planned in its own folder under
    ``root`` (one workflow copy shared by the targets, one for the audit)."""
    folders = {}
    out = {}
    here = Path.cwd()
    try:
        for name in names:
            kind = "audit" if name == "audit" else "workflow"
            if kind not in folders:
                make = audit_folder if kind == "audit" else workflow_folder
                folders[kind] = make(root / kind)
            os.chdir(folders[kind])
            configs = [AUDIT_CONFIG] if kind == "audit" else []
            start = time.perf_counter()
            out[name] = job_lines(LISTINGS[name], configs)
            print(f"{name}: {time.perf_counter() - start:.1f} s", file=sys.stderr)
    finally:
        os.chdir(here)
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--configfile", nargs="+", default=[])
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--write", type=Path, metavar="DIR", help="write LISTINGS' files here")
    parser.add_argument("targets", nargs="*")
    args = parser.parse_args(argv)
    if args.write:
        args.write.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory() as tmp:
            for name, lines in listings(Path(tmp), args.targets or list(LISTINGS)).items():
                (args.write / f"{name}.txt").write_text("".join(f"{line}\n" for line in lines))
        return
    for line in job_lines(args.targets, args.configfile, args.cores):
        print(line)


if __name__ == "__main__":
    main()
