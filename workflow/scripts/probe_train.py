"""Snakemake adapter: train one probe network."""

from stereovar.jobs.common import run_job
from stereovar.jobs.probe import train_job

run_job(
    snakemake.log[0],
    train_job,
    stores=dict(snakemake.input.items()),
    out=snakemake.output[0],
    **snakemake.params,
)
