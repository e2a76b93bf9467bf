"""Snakemake adapter: every network of one probe fold on its held-out scenes."""

from stereovar.jobs.common import run_job
from stereovar.jobs.probe import test_job

stores = {k: v for k, v in snakemake.input.items() if k != "networks"}
run_job(
    snakemake.log[0],
    test_job,
    stores=stores,
    networks=list(snakemake.input.networks),
    out=snakemake.output[0],
    **snakemake.params,
)
