"""Snakemake adapter: render and plot one scene's preview."""

from stereovar.jobs.common import run_job
from stereovar.jobs.preview import preview_job

run_job(
    snakemake.log[0],
    preview_job,
    spec=snakemake.input.spec,
    ground_truth=snakemake.input.ground_truth,
    out=snakemake.output[0],
    threads=snakemake.threads,
    **snakemake.params,
)
