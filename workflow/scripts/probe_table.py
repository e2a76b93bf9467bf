"""Snakemake adapter: the probe table, its training table, its figure and the verdict."""

from stereovar.jobs.common import run_job
from stereovar.jobs.probe import probe_table_job

run_job(
    snakemake.log[0],
    probe_table_job,
    tiles=list(snakemake.input.tiles),
    networks=list(snakemake.input.networks),
    planted=snakemake.input.get("planted"),
    outputs={k: snakemake.output[k] for k in ("csv", "md", "tex", "html")},
    training_outputs={k: snakemake.output[f"training_{k}"] for k in ("csv", "md", "tex", "html")},
    figure=snakemake.output.figure,
    verdict=snakemake.output.verdict,
    **snakemake.params,
)
