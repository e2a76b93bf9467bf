"""Snakemake adapter: stereovar.jobs.teaser_figure_job."""

from stereovar.jobs import run_job, teaser_figure_job

run_job(
    snakemake.log[0],
    teaser_figure_job,
    variance=snakemake.input.variance,
    warped=snakemake.input.warped,
    out=snakemake.output[0],
)
