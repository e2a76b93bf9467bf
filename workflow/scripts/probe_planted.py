"""Snakemake adapter: the planted control's strength and camera laws."""

from stereovar.jobs.common import run_job
from stereovar.jobs.probe import planted_job

run_job(
    snakemake.log[0],
    planted_job,
    stores=dict(snakemake.input.items()),
    out=snakemake.output[0],
    **snakemake.params,
)
