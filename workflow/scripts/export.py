"""Snakemake adapter: stereovar.jobs.audit.export_job."""

from stereovar.jobs.audit import export_job
from stereovar.jobs.common import run_job

run_job(
    snakemake.log[0],
    export_job,
    renders=dict(left=list(snakemake.input.left), right=list(snakemake.input.right)),
    variance=snakemake.input.variance,
    ground_truth=snakemake.input.ground_truth,
    out=snakemake.output[0],
    **snakemake.params,
)
