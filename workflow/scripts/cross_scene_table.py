"""Snakemake adapter: stereovar.jobs.cross_scene_job."""

from stereovar.jobs import cross_scene_job, run_job

run_job(
    snakemake.log[0],
    cross_scene_job,
    correlations=list(snakemake.input),
    outputs=dict(snakemake.output.items()),
    **snakemake.params,
)
