"""Cluster requests of the workflow's jobs (``resources:`` of the rules), each a function of
the job's wildcards and ``attempt`` where it depends on them, from the job's size
(:mod:`stereovar.resources`). Account, partition and GPU model come from the profile
(``profiles/slurm*``), never from here.
"""

from __future__ import annotations

import math

from .. import resources as sizing
from ..experiment import batch_seeds
from ..transforms import get_transform


def batch_size(wildcards) -> int:
    """Seeds per view in the job's ``{batch}`` wildcard (1 for a job without one).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> batch_size(SimpleNamespace(batch="0-3")), batch_size(SimpleNamespace())
    (4, 1)
    """
    batch = getattr(wildcards, "batch", None)
    return len(batch_seeds(batch)) if batch else 1


def render_resources(
    width: int,
    height: int,
    cluster: dict,
    *,
    n_views: int = 2,
    spp=None,
    gpu: bool = True,
    cpus=None,
    moments: bool = False,
) -> dict:
    """Memory, runtime and (with ``gpu``) GPU requests of a job rendering ``n_views`` views
    of each seed of its ``{batch}`` (one seed without one) at ``spp`` (the job's ``spp``
    wildcard when None); ``moments``: one view's two half renders (``spp`` samples in all)
    for the moments estimator.

    Parameters
    ----------
    width, height : int
        The image size in pixels (``resolution``).
    cluster : dict
        The ``cluster:`` config section (``render_samples_per_second``, ``render_threads``,
        ``gpus_per_render``, ``gpu_model``).

    Returns
    -------
    dict
        ``mem_mb`` and ``runtime`` (functions of ``wildcards`` and ``attempt``),
        ``cpus_per_task``, and ``gpu`` and ``gpu_model`` when the cluster gives renders GPUs.
    """

    def runtime(wildcards, attempt):
        return sizing.render_runtime(
            width,
            height,
            int(wildcards.spp if spp is None else spp),
            n_views * batch_size(wildcards),
            samples_per_second=cluster["render_samples_per_second"],
            attempt=attempt,
        )

    def mem_mb(wildcards, attempt):
        if moments:
            return sizing.moments_mem_mb(width, height, attempt=attempt)
        return sizing.render_mem_mb(width, height, batch=batch_size(wildcards), attempt=attempt)

    requests = {
        "mem_mb": mem_mb,
        "runtime": runtime,
        "cpus_per_task": cluster["render_threads"] if cpus is None else cpus,
    }
    if gpu and cluster["gpus_per_render"]:
        requests["gpu"] = cluster["gpus_per_render"]
        if cluster["gpu_model"]:
            requests["gpu_model"] = cluster["gpu_model"]
    return requests


def analysis_resources(width: int, height: int, images: int, n_reads: int) -> dict:
    """Memory and runtime requests of an analysis job holding ``images`` images of
    ``width`` x ``height`` at once and reading ``n_reads`` renders."""
    return {
        "mem_mb": lambda wildcards, attempt: sizing.analysis_mem_mb(
            width, height, images, attempt=attempt
        ),
        "runtime": lambda wildcards, attempt: sizing.analysis_runtime(
            width, height, n_reads, attempt=attempt
        ),
    }


def intervention_disparity(width: int, intervention: dict) -> int:
    r"""The largest disparity :math:`D` one scene's intervention is sized for, before its
    ground truth exists: ``intervention.max_disparity``, else
    :math:`\lceil 0.05\,W \rceil` plus ``intervention.disparity_margin``.

    Examples
    --------
    >>> intervention_disparity(320, {"max_disparity": None, "disparity_margin": 2})
    18
    >>> intervention_disparity(320, {"max_disparity": 40, "disparity_margin": 2})
    40
    """
    return intervention["max_disparity"] or math.ceil(0.05 * width) + intervention[
        "disparity_margin"
    ]


def intervention_resources(width: int, height: int, intervention: dict, n_seeds: int) -> dict:
    """Memory and runtime requests of one scene's intervention over ``n_seeds`` seeds
    (:math:`D` from :func:`intervention_disparity`), and its two CPUs."""
    d = intervention_disparity(width, intervention)
    return {
        "mem_mb": lambda wildcards, attempt: sizing.analysis_mem_mb(
            width, height, 24, attempt=attempt
        ),
        "runtime": lambda wildcards, attempt: sizing.intervention_runtime(
            width, height, n_seeds, d + 1, attempt=attempt
        ),
        "cpus_per_task": 2,
    }


def calibration_resources(
    width: int, height: int, calibration: dict, draws: int, transforms: list
) -> dict:
    """Memory and runtime requests of one scene's calibration: every frame of both views,
    the transformed stacks and the renders in memory (:math:`4N + 16` images, :math:`N` =
    ``draws`` frames per view), and :func:`stereovar.resources.calibration_runtime` with the
    expensive transforms (the denoisers) counted apart.

    Parameters
    ----------
    calibration : dict
        The ``calibration:`` config section.
    transforms : list of str
        The calibrated transforms, ``"none"`` first.
    """
    denoisers = [t for t in transforms[1:] if get_transform(t).expensive]

    def runtime(wildcards, attempt):
        return sizing.calibration_runtime(
            width,
            height,
            draws,
            replicates=int(calibration["replicates"]),
            designs=2 + len(calibration["strengths"]),
            transforms=len(transforms) - len(denoisers),
            denoised_replicates=int(calibration["denoised_replicates"]),
            denoisers=len(denoisers),
            pipeline_replicates=int(calibration.get("pipeline_replicates", 0)),
            pipeline_designs=sum(
                2 if str(p).startswith("srgb8_") else 1 for p in calibration.get("pipelines", [])
            ),
            attempt=attempt,
        )

    return {
        **analysis_resources(width, height, images=4 * draws + 16, n_reads=2 * draws),
        "runtime": runtime,
    }
