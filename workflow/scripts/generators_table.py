"""Snakemake adapter: the generator table, its figure and its verdicts' calibration."""

from stereovar.jobs.common import run_job
from stereovar.jobs.generators import generators_table_job

outputs = {k: snakemake.output[k] for k in ("csv", "md", "tex", "html")}
run_job(
    snakemake.log[0],
    generators_table_job,
    runs=snakemake.params.runs,
    outputs=outputs,
    figure=snakemake.output.figure,
    calibration=snakemake.output.calibration,
)
