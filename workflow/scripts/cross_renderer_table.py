"""Snakemake adapter: stereovar.jobs.tables.cross_renderer_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.tables import cross_renderer_job

run_job(
    snakemake.log[0],
    cross_renderer_job,
    correlations={r: list(getattr(snakemake.input, r)) for r in snakemake.params.renderers},
    outputs=dict(snakemake.output.items()),
    spp=snakemake.params.spp,
)
