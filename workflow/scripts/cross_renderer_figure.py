"""Snakemake adapter: stereovar.jobs.figures.cross_renderer_figure_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.figures import cross_renderer_figure_job

renderers = snakemake.params.renderers
run_job(
    snakemake.log[0],
    cross_renderer_figure_job,
    variances={r: getattr(snakemake.input, f"variance_{r}") for r in renderers},
    correlations={r: getattr(snakemake.input, f"correlation_{r}") for r in renderers},
    out=snakemake.output[0],
)
