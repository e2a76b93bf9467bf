"""Snakemake adapter: the dose-response table."""

from stereovar.jobs.common import run_job
from stereovar.jobs.dose_response import dose_response_table_job

run_job(
    snakemake.log[0],
    dose_response_table_job,
    rows=list(snakemake.input.rows),
    outputs={k: snakemake.output[k] for k in ("csv", "md", "tex", "html")},
    nulls=snakemake.input.nulls,
    **dict(snakemake.params.items()),
)
