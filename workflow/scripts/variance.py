"""Snakemake adapter: stereovar.jobs.variance_job."""

from stereovar.jobs import run_job, variance_job

run_job(
    snakemake.log[0],
    variance_job,
    left=snakemake.input.left,
    right=snakemake.input.right,
    out=snakemake.output[0],
)
