"""Snakemake adapter: one scene's residual correlations and image quality."""

from stereovar.jobs.common import run_job
from stereovar.jobs.mitigations import mitigation_scene_job

run_job(
    snakemake.log[0],
    mitigation_scene_job,
    left=list(snakemake.input.left),
    right=list(snakemake.input.right),
    ground_truth=snakemake.input.ground_truth,
    reference={
        "left": snakemake.input.reference_left,
        "right": snakemake.input.reference_right,
    },
    out=snakemake.output[0],
    **snakemake.params,
)
