"""What an experiment config asks for: scene/SPP pairs, seed batches and the stores they read.

Shared by the workflow's target lists (``workflow/rules/inputs/targets.smk``) and the benchmarks, so
both enumerate exactly the same renders. Every path comes from :mod:`stereovar.layout`
(re-exported here): renders under ``results/{source}[/{transform}]/renders/``, everything
computed from them under ``results/{source}[/{transform}]/{estimator}/``.
"""

from __future__ import annotations

from .layout import (
    AUDIT_PREFIX,
    NONE,
    audit_source,
    ground_truth_store,
    is_audit,
    moment_store,
    render_store,
    run_prefix,
)
from .rig import VIEWS

__all__ = [
    "AUDIT_PREFIX",
    "VIEWS",
    "audit_source",
    "batch_label",
    "estimator_stores",
    "ground_truth_store",
    "is_audit",
    "intervention_renders",
    "moment_store",
    "render_store",
    "render_stores",
    "run_prefix",
    "scene_spp_pairs",
    "seed_batches",
]


def scene_spp_pairs(config: dict) -> list[tuple[str, int]]:
    """(scene, spp) pairs to render: every scene at the main SPP, the sweep scene at each SPP.

    Parameters
    ----------
    config : dict
        A validated workflow config (:func:`stereovar.config.validate_config`).

    Returns
    -------
    list of (str, int)
        Main-SPP pairs in ``scenes`` order, then the sweep scene's other SPPs ascending.
    """
    render = config["render"]
    main = int(render["spp"])
    pairs = [(scene, main) for scene in config["scenes"]]
    sweep = render["spp_sweep"]
    pairs += [(sweep["scene"], int(spp)) for spp in sorted(sweep["spp"]) if spp != main]
    return pairs


def seed_batches(n_seeds: int, seeds_per_job: int) -> list[list[int]]:
    """Seed indices ``0..n_seeds-1`` cut into aligned batches of ``seeds_per_job``.

    Batches start at multiples of ``seeds_per_job``, so raising ``n_seeds`` by a multiple of
    it adds batches without changing the existing ones.
    """
    return [
        list(range(start, min(start + seeds_per_job, n_seeds)))
        for start in range(0, n_seeds, seeds_per_job)
    ]


def batch_label(seeds) -> str:
    """The ``{batch}`` wildcard of a batch of consecutive seed indices: ``first-last``."""
    seeds = list(seeds)
    if not seeds or seeds != list(range(seeds[0], seeds[-1] + 1)):
        raise ValueError(f"a batch is a run of consecutive seed indices, got {seeds}")
    return f"{seeds[0]}-{seeds[-1]}"


def batch_seeds(label: str) -> list[int]:
    """The seed indices of a ``first-last`` batch label (inverse of :func:`batch_label`)."""
    first, _, last = str(label).partition("-")
    if not (first.isdigit() and last.isdigit()) or int(last) < int(first):
        raise ValueError(f"a seed batch is 'first-last' with first <= last, got {label!r}")
    return list(range(int(first), int(last) + 1))


def seed_stores(
    config: dict, scene: str, spp, n_seeds: int | None = None, transform: str = NONE
) -> dict:
    """View to the render stores of seed indices ``0..n_seeds-1`` (``render.n_seeds`` by
    default) of one scene at ``spp`` after ``transform``, in ``render.seeds_per_job``
    batches."""
    render = config["render"]
    n = int(render["n_seeds"] if n_seeds is None else n_seeds)
    batches = seed_batches(n, int(render["seeds_per_job"]))
    source = render["renderer"]
    return {
        view: [render_store(source, scene, view, spp, batch_label(b), transform) for b in batches]
        for view in VIEWS
    }


def estimator_stores(
    config: dict, scene: str, spp, estimator: str | None = None, transform: str = NONE
) -> dict:
    """View to the stores ``estimator`` (``render.estimator`` by default) reads for one
    scene at ``spp`` after ``transform``: what the estimator declares it reads
    (:attr:`stereovar.estimators.base.VarianceEstimator.reads`), every seed batch
    (``renders``) or the one moment store (``moments``)."""
    from .estimators import ESTIMATORS

    estimator = estimator or config["render"].get("estimator", "seeds")
    if ESTIMATORS.get(estimator).reads == "moments":
        renderer = config["render"]["renderer"]
        return {view: [moment_store(renderer, scene, view, spp, transform)] for view in VIEWS}
    return seed_stores(config, scene, spp, transform=transform)


def intervention_renders(config: dict) -> tuple[int, int]:
    """``(N, SPP)`` of the intervention's seed renders: ``intervention.n_seeds`` and
    ``intervention.spp``, each defaulting to the ``render`` value."""
    render, iv = config["render"], config.get("intervention", {})
    n = iv.get("n_seeds") or render["n_seeds"]
    spp = iv.get("spp") or render["spp"]
    return int(n), int(spp)


def render_stores(config: dict) -> list[str]:
    """Every render and moment store the config asks for: the estimator's at every (scene,
    SPP) pair, then the intervention's seed renders of every scene."""
    n, spp = intervention_renders(config)
    stores = [
        path
        for scene, scene_spp in scene_spp_pairs(config)
        for paths in estimator_stores(config, scene, scene_spp).values()
        for path in paths
    ]
    for scene in config["scenes"]:
        for paths in seed_stores(config, scene, spp, n).values():
            stores += [p for p in paths if p not in stores]
    return stores
