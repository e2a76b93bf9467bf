"""Snakemake adapter: stereovar.jobs.figures.statistics_dot_figure_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.figures import statistics_dot_figure_job

run_job(
    snakemake.log[0],
    statistics_dot_figure_job,
    correlations=list(snakemake.input),
    out=snakemake.output[0],
    **snakemake.params,
)
