"""Snakemake adapter: stereovar.jobs.claims.statistics_job."""

from stereovar.jobs.claims import statistics_job
from stereovar.jobs.common import run_job

outputs = dict(snakemake.output.items())
run_job(
    snakemake.log[0],
    statistics_job,
    correlations=list(snakemake.input.correlations),
    curves=list(snakemake.input.curves),
    outputs={k: v for k, v in outputs.items() if not k.startswith("curve_")},
    curve_outputs={k[len("curve_") :]: v for k, v in outputs.items() if k.startswith("curve_")},
    **snakemake.params,
)
