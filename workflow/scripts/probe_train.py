"""Snakemake adapter: train one probe network."""

from stereovar.jobs.common import run_job
from stereovar.jobs.probe import train_job

stores = {k: v for k, v in snakemake.input.items() if k != "planted"}
run_job(
    snakemake.log[0],
    train_job,
    stores=stores,
    planted=snakemake.input.get("planted"),
    out=snakemake.output[0],
    **snakemake.params,
)
