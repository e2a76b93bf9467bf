"""Snakemake adapter: the calibration table, the matched nulls and the figure."""

from stereovar.jobs.calibration import calibration_table_job
from stereovar.jobs.common import run_job

run_job(
    snakemake.log[0],
    calibration_table_job,
    rows=list(snakemake.input),
    outputs={"csv": snakemake.output.csv, "md": snakemake.output.md},
    nulls=snakemake.output.nulls,
    figure=snakemake.output.figure,
)
