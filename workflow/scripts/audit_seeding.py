"""Snakemake adapter: stereovar.jobs.audit.seeding_job."""

from stereovar.jobs.audit import seeding_job
from stereovar.jobs.common import run_job

run_job(
    snakemake.log[0],
    seeding_job,
    left=list(snakemake.input.left),
    right=list(snakemake.input.right),
    ground_truth=snakemake.input.ground_truth,
    out=snakemake.output[0],
    **snakemake.params,
)
