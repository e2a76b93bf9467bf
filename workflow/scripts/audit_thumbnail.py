"""Snakemake adapter: stereovar.jobs.audit.thumbnail_job."""

from stereovar.jobs.audit import thumbnail_job
from stereovar.jobs.common import run_job

run_job(
    snakemake.log[0],
    thumbnail_job,
    left=list(snakemake.input.left),
    ground_truth=snakemake.input.ground_truth,
    out=snakemake.output[0],
)
