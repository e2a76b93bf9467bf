"""Snakemake adapter: trace one scene's ground truth."""

from stereovar.jobs.common import run_job
from stereovar.jobs.ground_truth import ground_truth_job

run_job(
    snakemake.log[0],
    ground_truth_job,
    spec=snakemake.input.spec,
    out=snakemake.output[0],
    threads=snakemake.threads,
    **snakemake.params,
)
