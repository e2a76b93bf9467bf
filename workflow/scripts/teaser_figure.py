"""Snakemake adapter: stereovar.jobs.figures.teaser_figure_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.figures import teaser_figure_job

run_job(
    snakemake.log[0],
    teaser_figure_job,
    variance=snakemake.input.variance,
    warped=snakemake.input.warped,
    out=snakemake.output[0],
)
