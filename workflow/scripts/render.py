"""Snakemake adapter: render one batch of seeds of both views."""

from stereovar.jobs.common import run_job
from stereovar.jobs.render import render_job

run_job(
    snakemake.log[0],
    render_job,
    spec=snakemake.input.spec,
    outputs={"left": snakemake.output.left, "right": snakemake.output.right},
    threads=snakemake.threads,
    cache=snakemake.config["render"]["cache"],
    **snakemake.params,
)
