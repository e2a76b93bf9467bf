"""Snakemake adapter: stereovar.jobs.variance.variance_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.variance import variance_job

run_job(
    snakemake.log[0],
    variance_job,
    left=snakemake.input.left,
    right=snakemake.input.right,
    out=snakemake.output[0],
    # read here, not a param: switching it must not rerun finished jobs
    allow_mixed_backends=snakemake.config["render"]["allow_mixed_backends"],
    **snakemake.params,
)
