"""Snakemake adapter: one scene's moment field against its N-seed reference."""

from stereovar.jobs.common import run_job
from stereovar.jobs.estimators import estimator_check_job

inputs = snakemake.input
run_job(
    snakemake.log[0],
    estimator_check_job,
    moments={"left": [inputs.moments_left], "right": [inputs.moments_right]},
    seeds={"left": list(inputs.seeds_left), "right": list(inputs.seeds_right)},
    ground_truth=inputs.ground_truth,
    outputs={"fields": snakemake.output.fields, "rows": snakemake.output.rows},
    **snakemake.params,
)
