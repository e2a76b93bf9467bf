"""Snakemake adapter: train the probe networks of one condition, architecture, variant and
fold, one per training seed."""

from stereovar.jobs.common import run_job
from stereovar.jobs.probe import train_job

stores = {k: v for k, v in snakemake.input.items() if k != "planted"}
run_job(
    snakemake.log[0],
    train_job,
    stores=stores,
    planted=snakemake.input.get("planted"),
    outs=list(snakemake.output),
    **snakemake.params,
)
