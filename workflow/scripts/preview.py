"""Snakemake adapter: render and plot one scene's preview."""

from stereovar.jobs import preview_job, run_job

run_job(
    snakemake.log[0],  # noqa: F821
    preview_job,
    spec=snakemake.input.spec,  # noqa: F821
    ground_truth=snakemake.input.ground_truth,  # noqa: F821
    out=snakemake.output[0],  # noqa: F821
    threads=snakemake.threads,  # noqa: F821
    **snakemake.params,  # noqa: F821
)
