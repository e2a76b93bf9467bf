"""Snakemake adapter: list the frames `stereovar probe` runs the user's model on."""

from stereovar.jobs.common import run_job
from stereovar.jobs.probe_model import write_manifest

run_job(
    snakemake.log[0],
    write_manifest,
    stores=dict(snakemake.input.items()),
    scenes=snakemake.params.scenes,
    out=snakemake.output[0],
)
