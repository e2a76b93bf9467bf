"""Snakemake adapter: one scene's residual correlations and image quality."""

from stereovar.jobs.common import run_job
from stereovar.jobs.mitigations import mitigation_scene_job


def stores(paths):
    """Render stores as a list, or a reference's one moment store as its path."""
    paths = [paths] if isinstance(paths, str) else list(paths)
    if len(paths) == 1 and paths[0].endswith("moments.zarr"):
        return paths[0]
    return paths


run_job(
    snakemake.log[0],
    mitigation_scene_job,
    left=stores(snakemake.input.left),
    right=stores(snakemake.input.right),
    ground_truth=snakemake.input.ground_truth,
    reference={
        view: stores(paths)
        for view, paths in (
            ("left", snakemake.input.reference_left),
            ("right", snakemake.input.reference_right),
        )
    },
    out=snakemake.output[0],
    **snakemake.params,
)
