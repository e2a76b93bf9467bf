"""Snakemake adapter: stereovar.jobs.intervention.intervention_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.intervention import intervention_job

run_job(
    snakemake.log[0],
    intervention_job,
    left=snakemake.input.left,
    right=snakemake.input.right,
    ground_truth=snakemake.input.ground_truth,
    out=snakemake.output.metrics,
    margins=snakemake.output.margins,
    workers=snakemake.threads,
    **snakemake.params,
)
