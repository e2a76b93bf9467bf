"""Snakemake adapter: render one view's two half renders for the moments estimator."""

from stereovar.jobs.common import run_job
from stereovar.jobs.render import moments_job

run_job(
    snakemake.log[0],
    moments_job,
    spec=snakemake.input.spec,
    out=snakemake.output[0],
    threads=snakemake.threads,
    cache=snakemake.config["render"]["cache"],
    **snakemake.params,
)
