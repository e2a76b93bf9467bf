"""Snakemake adapter: generate one procedural scene spec."""

from stereovar.jobs.common import run_job
from stereovar.jobs.scenes import generate_scene_job

run_job(
    snakemake.log[0],
    generate_scene_job,
    out=snakemake.output[0],
    seed=snakemake.params.seed,
)
