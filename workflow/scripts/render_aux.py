"""Snakemake adapter: one view's auxiliary passes (albedo, normal) for the denoiser."""

from stereovar.jobs.common import run_job
from stereovar.jobs.transform import aux_job

run_job(
    snakemake.log[0],
    aux_job,
    spec=snakemake.input.spec,
    out=snakemake.output[0],
    threads=snakemake.threads,
    **snakemake.params,
)
