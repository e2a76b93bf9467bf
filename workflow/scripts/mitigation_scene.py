"""Snakemake adapter: one scene's residual correlations and image quality."""

from stereovar.jobs.common import run_job
from stereovar.jobs.mitigation_scene import mitigation_scene_job


def stores(paths) -> list:
    """Named input as a list of paths (Snakemake gives one path as a string)."""
    return [paths] if isinstance(paths, str) else list(paths)


params = dict(snakemake.params.items())
moments = params.pop("reference_moments")
run_job(
    snakemake.log[0],
    mitigation_scene_job,
    left=stores(snakemake.input.left),
    right=stores(snakemake.input.right),
    ground_truth=snakemake.input.ground_truth,
    reference={
        view: stores(paths)[0] if moments else stores(paths)
        for view, paths in (
            ("left", snakemake.input.reference_left),
            ("right", snakemake.input.reference_right),
        )
    },
    out=snakemake.output[0],
    **params,
)
