"""Snakemake adapter: stereovar.jobs.figures.rho_vs_seeds_figure_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.figures import rho_vs_seeds_figure_job

run_job(
    snakemake.log[0],
    rho_vs_seeds_figure_job,
    curve_table=snakemake.input[0],
    out=snakemake.output[0],
)
