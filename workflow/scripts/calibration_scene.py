"""Snakemake adapter: one scene's calibration replicates."""

from stereovar.jobs.calibration import calibration_scene_job
from stereovar.jobs.common import run_job

aux = {
    view: snakemake.input[f"aux_{view}"]
    for view in ("left", "right")
    if f"aux_{view}" in snakemake.input.keys()
}
renders = {
    view: list(snakemake.input[f"renders_{view}"])
    for view in ("left", "right")
    if f"renders_{view}" in snakemake.input.keys()
}
output_renders = {
    view: list(snakemake.input[f"output_{view}"])
    for view in ("left", "right")
    if f"output_{view}" in snakemake.input.keys()
}
run_job(
    snakemake.log[0],
    calibration_scene_job,
    variance=snakemake.input.variance,
    ground_truth=snakemake.input.ground_truth,
    out=snakemake.output[0],
    aux=aux or None,
    renders=renders or None,
    output_renders=output_renders or None,
    **dict(snakemake.params.items()),
)
