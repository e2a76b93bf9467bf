"""Snakemake adapter: stereovar.jobs.audit.verdict_job."""

from stereovar.io.contracts import config_digest
from stereovar.jobs.audit import verdict_job
from stereovar.jobs.common import run_job

run_job(
    snakemake.log[0],
    verdict_job,
    correlations=list(snakemake.input.correlations),
    interventions=list(snakemake.input.interventions),
    teasers=list(snakemake.input.teasers),
    thumbnails=list(snakemake.input.thumbnails),
    seeding=list(snakemake.input.seeding),
    imports=list(snakemake.input.imports),
    mitigations=(list(snakemake.input.mitigations) or [None])[0],
    mitigation_figure=(list(snakemake.input.mitigation_figure) or [None])[0],
    dose=(list(snakemake.input.dose) or [None])[0],
    probe=(list(snakemake.input.probe) or [None])[0],
    probe_figure=(list(snakemake.input.probe_figure) or [None])[0],
    calibration=snakemake.input.calibration,
    nulls=snakemake.input.nulls,
    statistics_figure=snakemake.input.statistics_figure,
    variance=list(snakemake.input.variance),
    warped=list(snakemake.input.warped),
    ground_truth=list(snakemake.input.ground_truth),
    outputs=dict(snakemake.output.items()),
    # read here, not a param: the page records the config, a change of it reruns nothing
    config_digest=config_digest(dict(snakemake.config)),
    **snakemake.params,
)
