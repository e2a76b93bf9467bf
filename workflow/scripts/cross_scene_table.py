"""Snakemake adapter: stereovar.jobs.tables.cross_scene_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.tables import cross_scene_job

run_job(
    snakemake.log[0],
    cross_scene_job,
    correlations=list(snakemake.input),
    outputs=dict(snakemake.output.items()),
    **snakemake.params,
)
