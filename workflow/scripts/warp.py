"""Snakemake adapter: stereovar.jobs.correlation.warp_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.correlation import warp_job

run_job(
    snakemake.log[0],
    warp_job,
    variance=snakemake.input.variance,
    ground_truth=snakemake.input.ground_truth,
    out=snakemake.output[0],
)
