"""Snakemake adapter: stereovar.jobs.correlation.correlation_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.correlation import correlation_job

run_job(
    snakemake.log[0],
    correlation_job,
    variance=snakemake.input.variance,
    warped=snakemake.input.warped,
    ground_truth=snakemake.input.ground_truth,
    out=snakemake.output.rows,
    curve=snakemake.output.curve,
    **snakemake.params,
)
