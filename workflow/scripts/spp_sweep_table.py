"""Snakemake adapter: stereovar.jobs.spp_sweep_job."""

from stereovar.jobs import run_job, spp_sweep_job

run_job(
    snakemake.log[0],
    spp_sweep_job,
    correlations=snakemake.input.correlations,
    variances=snakemake.input.variances,
    warped=snakemake.input.warped,
    outputs={k: snakemake.output[k] for k in ("csv", "md", "tex")},
    fit_outputs={k: snakemake.output["fit_" + k] for k in ("csv", "md", "tex")},
)
