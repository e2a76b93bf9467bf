"""Snakemake adapter: stereovar.jobs.claims.claims_job."""

from stereovar.io.contracts import config_digest
from stereovar.jobs.claims import claims_job
from stereovar.jobs.common import run_job

outputs = dict(snakemake.output.items())
run_job(
    snakemake.log[0],
    claims_job,
    correlations=list(snakemake.input.correlations),
    curves=list(snakemake.input.curves),
    sweep=snakemake.input.sweep,
    interventions=list(snakemake.input.interventions),
    mitigations=(list(snakemake.input.mitigations) or [None])[0],
    probe=(list(snakemake.input.probe) or [None])[0],
    outputs={k: v for k, v in outputs.items() if k != "summary"},
    summary=outputs["summary"],
    # read here, not a param: a config change outside the analysis must not rerun the claims
    config_digest=config_digest(dict(snakemake.config)),
    **snakemake.params,
)
