"""Snakemake adapter: stereovar.jobs.figures.material_scatter_figure_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.figures import material_scatter_figure_job

run_job(
    snakemake.log[0],
    material_scatter_figure_job,
    variance=snakemake.input.variance,
    warped=snakemake.input.warped,
    ground_truth=snakemake.input.ground_truth,
    out=snakemake.output[0],
)
