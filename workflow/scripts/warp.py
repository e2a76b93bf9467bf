"""Snakemake adapter: stereovar.jobs.warp_job."""

from stereovar.jobs import run_job, warp_job

run_job(
    snakemake.log[0],
    warp_job,
    variance=snakemake.input.variance,
    ground_truth=snakemake.input.ground_truth,
    out=snakemake.output[0],
)
