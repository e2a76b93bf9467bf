"""Snakemake adapter: stereovar.jobs.figures.margin_figure_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.figures import margin_figure_job

run_job(snakemake.log[0], margin_figure_job, margins=list(snakemake.input), out=snakemake.output[0])
