"""Snakemake adapter: render one batch of seeds of both views."""

from stereovar.jobs import render_job, run_job

run_job(
    snakemake.log[0],
    render_job,
    spec=snakemake.input.spec,
    outputs=list(snakemake.output),
    threads=snakemake.threads,
    **snakemake.params,
)
