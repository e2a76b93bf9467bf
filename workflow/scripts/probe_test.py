"""Snakemake adapter: every network of one probe condition, architecture and fold on its
held-out scenes."""

from stereovar.jobs.common import run_job
from stereovar.jobs.probe import test_job

stores = {k: v for k, v in snakemake.input.items() if k not in ("networks", "planted")}
run_job(
    snakemake.log[0],
    test_job,
    stores=stores,
    networks=list(snakemake.input.networks),
    planted=snakemake.input.get("planted"),
    out=snakemake.output[0],
    **snakemake.params,
)
