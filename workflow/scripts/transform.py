"""Snakemake adapter: a store transform on one batch of one view's renders."""

from stereovar.jobs.common import run_job
from stereovar.jobs.transform import transform_job

run_job(
    snakemake.log[0],
    transform_job,
    renders=list(snakemake.input.renders),
    aux=snakemake.input.get("aux"),
    out=snakemake.output[0],
    **snakemake.params,
)
