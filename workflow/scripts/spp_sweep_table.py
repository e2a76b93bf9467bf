"""Snakemake adapter: stereovar.jobs.tables.spp_sweep_job."""

from stereovar.jobs.common import run_job
from stereovar.jobs.tables import spp_sweep_job

run_job(
    snakemake.log[0],
    spp_sweep_job,
    correlations=snakemake.input.correlations,
    variances=snakemake.input.variances,
    warped=snakemake.input.warped,
    outputs={k: snakemake.output[k] for k in ("csv", "md", "tex", "html")},
    fit_outputs={k: snakemake.output["fit_" + k] for k in ("csv", "md", "tex", "html")},
)
