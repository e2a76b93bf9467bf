"""Snakemake adapter: the user's own network on the counterfactual inputs of every frame."""

from stereovar.jobs.common import run_job
from stereovar.jobs.probe_model import probe_model_job

stores = {k: v for k, v in snakemake.input.items() if k != "weights"}
outputs = {k: snakemake.output[k] for k in ("csv", "md", "tex", "html")}
run_job(
    snakemake.log[0],
    probe_model_job,
    stores=stores,
    outputs=outputs,
    weights=snakemake.input.weights,
    threads=snakemake.threads,
    **snakemake.params,
)
