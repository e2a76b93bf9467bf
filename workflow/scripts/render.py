"""Snakemake adapter: render one batch of seeds of both views."""

from stereovar.jobs import render_job, run_job

run_job(
    snakemake.log[0],  # noqa: F821
    render_job,
    spec=snakemake.input.spec,  # noqa: F821
    outputs=list(snakemake.output),  # noqa: F821
    threads=snakemake.threads,  # noqa: F821
    **snakemake.params,  # noqa: F821
)
