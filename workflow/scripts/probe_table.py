"""Snakemake adapter: the probe table, its figure and the verdict."""

from stereovar.jobs.common import run_job
from stereovar.jobs.probe import probe_table_job

run_job(
    snakemake.log[0],
    probe_table_job,
    tiles=list(snakemake.input),
    outputs={k: snakemake.output[k] for k in ("csv", "md", "tex", "html")},
    figure=snakemake.output.figure,
    verdict=snakemake.output.verdict,
    **snakemake.params,
)
