"""Snakemake adapter: stereovar.jobs.audit.import_job."""

from stereovar.jobs.audit import import_job
from stereovar.jobs.common import run_job

run_job(
    snakemake.log[0],
    import_job,
    settings=dict(snakemake.config["audit"]),
    frame=snakemake.wildcards.scene,
    workers=snakemake.threads,
    fingerprint=snakemake.params.fingerprint,
)
