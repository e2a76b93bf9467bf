"""Snakemake adapter: the mitigation table and its trade-off figure."""

from stereovar.jobs.common import run_job
from stereovar.jobs.mitigations import mitigations_table_job

run_job(
    snakemake.log[0],
    mitigations_table_job,
    runs=snakemake.params.runs,
    outputs={k: snakemake.output[k] for k in ("csv", "md", "tex", "html")},
    figure=snakemake.output.figure,
    headline={k: snakemake.output[f"headline_{k}"] for k in ("csv", "md", "tex", "html")},
    nulls=snakemake.input.nulls,
    calibration=list(snakemake.input.calibration),
)
