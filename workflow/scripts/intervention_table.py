"""Snakemake adapter: stereovar.jobs.intervention.intervention_table_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.intervention import intervention_table_job

run_job(
    snakemake.log[0],
    intervention_table_job,
    inputs=list(snakemake.input),
    outputs=dict(snakemake.output.items()),
)
