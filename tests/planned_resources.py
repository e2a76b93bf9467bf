"""Each job a dry run plans, with its resource requests, read from Snakemake's API.

Run as a script in a workflow folder::

    python tests/planned_resources.py --configfile tiny.yaml TARGET ...

It prints one JSON list: a ``{"rule", "jobid", "resources"}`` entry per job, from the
job-info log records of a dry run (which do not depend on the order in which Snakemake prints
ready jobs), and a ``{"group", "rules", "resources"}`` entry per group job with the requests
Snakemake submits for it to a cluster executor (``GroupResources.basic_layered`` with
``run_local=False``: jobs that can run at once inside the group are summed, successive
levels take the maximum). Locally, group jobs are inactive and every job runs on its own.
"""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

from snakemake.api import SnakemakeApi
from snakemake.logging import LogEvent
from snakemake.resources import GroupResources
from snakemake.settings.types import (
    ConfigSettings,
    DAGSettings,
    OutputSettings,
    Quietness,
    ResourceSettings,
)

NUMERIC = (int, float)


def plain(resources) -> dict:
    """Numeric resources of a job, as a dict."""
    return {k: v for k, v in dict(resources).items() if isinstance(v, NUMERIC)}


class Collect(logging.Handler):
    """Keeps the job-info and group-info records of a dry run."""

    def __init__(self):
        super().__init__()
        self.jobs: list[dict] = []
        self.groups: list[dict] = []

    def emit(self, record):
        event = getattr(record, "event", None)
        if event == LogEvent.JOB_INFO:
            self.jobs.append(
                {"rule": record.rule_name, "jobid": record.jobid,
                 "resources": plain(record.resources)}
            )
        elif event == LogEvent.GROUP_INFO:
            member = next(iter(record.jobs))
            group = member.dag.get_job_group(member)
            submitted = GroupResources.basic_layered(
                toposorted_jobs=group.toposorted,
                constraints=group.global_resources,
                run_local=False,
                additive_resources=["runtime"],
                sortby=["runtime"],
            )
            self.groups.append(
                {"group": record.group_id, "rules": sorted(j.rule.name for j in record.jobs),
                 "resources": plain(submitted)}
            )


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--configfile", nargs="+", type=Path, default=[])
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("targets", nargs="*")
    args = parser.parse_args(argv)
    collect = Collect()
    with SnakemakeApi(OutputSettings(quiet={Quietness.ALL})) as api:
        workflow = api.workflow(
            resource_settings=ResourceSettings(cores=args.cores),
            config_settings=ConfigSettings(configfiles=args.configfile),
            snakefile=Path("Snakefile"),
            workdir=Path("."),
        )
        dag = workflow.dag(dag_settings=DAGSettings(targets=set(args.targets)))
        # Snakemake's logging set-up replaces handlers when the workflow is read: attach now
        logging.getLogger("snakemake.logging").addHandler(collect)
        try:
            dag.execute_workflow(executor="dryrun")
        finally:
            logging.getLogger("snakemake.logging").removeHandler(collect)
    print(json.dumps(collect.jobs + collect.groups))


if __name__ == "__main__":
    main()
