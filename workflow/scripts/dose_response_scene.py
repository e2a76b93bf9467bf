"""Snakemake adapter: one scene's dose-response rows."""

from stereovar.jobs.common import run_job
from stereovar.jobs.dose_response import dose_response_scene_job

renders = {}
for key in snakemake.input.keys():
    if key.startswith("renders_"):
        _, multiple, view = key.split("_")
        renders.setdefault(int(multiple), {})[view] = list(snakemake.input[key])
run_job(
    snakemake.log[0],
    dose_response_scene_job,
    variance=snakemake.input.variance,
    ground_truth=snakemake.input.ground_truth,
    out=snakemake.output[0],
    renders=renders,
    **dict(snakemake.params.items()),
)
