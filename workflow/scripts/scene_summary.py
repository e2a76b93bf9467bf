"""Snakemake adapter: tabulate glass fraction and disparity range per scene."""

from stereovar.jobs.common import run_job
from stereovar.jobs.scenes import scene_summary_job

run_job(
    snakemake.log[0],
    scene_summary_job,
    ground_truths=list(snakemake.input),
    outputs=dict(snakemake.output.items()),
)
