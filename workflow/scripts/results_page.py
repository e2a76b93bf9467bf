"""Snakemake adapter: stereovar.jobs.claims.results_page_job."""

from stereovar.jobs.claims import results_page_job
from stereovar.jobs.common import run_job

run_job(
    snakemake.log[0],
    results_page_job,
    claims=snakemake.input.claims,
    summary=snakemake.input.summary,
    figures=list(snakemake.input.figures),
    tables=list(snakemake.input.tables),
    mitigations=(list(snakemake.input.mitigations) or [None])[0],
    mitigation_figure=(list(snakemake.input.mitigation_figure) or [None])[0],
    dose=(list(snakemake.input.dose) or [None])[0],
    probe=(list(snakemake.input.probe) or [None])[0],
    probe_figure=(list(snakemake.input.probe_figure) or [None])[0],
    generators=list(snakemake.input.generators),
    generators_figure=(list(snakemake.input.generators_figure) or [None])[0],
    calibration=snakemake.input.calibration,
    out=snakemake.output[0],
    **snakemake.params,
)
