"""Snakemake adapter: stereovar.jobs.margin_figure_job."""

from stereovar.jobs import margin_figure_job, run_job

run_job(snakemake.log[0], margin_figure_job, margins=list(snakemake.input), out=snakemake.output[0])
