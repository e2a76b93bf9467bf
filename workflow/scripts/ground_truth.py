"""Snakemake adapter: trace one scene's ground truth."""

from stereovar.jobs import ground_truth_job, run_job

run_job(
    snakemake.log[0],  # noqa: F821
    ground_truth_job,
    spec=snakemake.input.spec,  # noqa: F821
    out=snakemake.output[0],  # noqa: F821
    threads=snakemake.threads,  # noqa: F821
    **snakemake.params,  # noqa: F821
)
