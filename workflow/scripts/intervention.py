"""Snakemake adapter: stereovar.jobs.intervention_job."""

from stereovar.jobs import intervention_job, run_job

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
