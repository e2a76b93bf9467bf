"""What an experiment config asks for: scene/SPP pairs, seed batches and result paths.

Shared by the workflow's target lists (``workflow/rules/common.smk``) and the benchmarks, so
both enumerate exactly the same renders. The result paths name the renderer and the
estimator that made them:

``results/{renderer}/renders/{scene}/{view}/spp{spp}/seeds{first}-{last}.zarr``
    one batch of renders of one view (:mod:`stereovar.io.renders`), for the ``seeds``
    estimator and the intervention;
``results/{renderer}/renders/{scene}/{view}/spp{spp}/moments.zarr``
    the two half renders' sample moments of one view (:mod:`stereovar.io.moments`), for the
    ``moments`` estimator;
``results/{renderer}/{estimator}/...``
    everything computed from the renders: variance, warped, correlation, intervention,
    tables and figures.

An audit of renders made elsewhere (:mod:`stereovar.audit`) is a source named
``audit/{name}`` in place of the renderer: its imported renders sit under
``results/audit/{name}/renders/``, its ground truth under
``results/audit/{name}/ground_truth/{frame}.zarr`` (:func:`ground_truth_store`) and
everything computed from them under ``results/audit/{name}/seeds/``.
"""

from __future__ import annotations

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


def render_store(renderer: str, scene: str, view: str, spp, batch) -> str:
    """Path of one batch of renders:
    ``results/{renderer}/renders/{scene}/{view}/spp{spp}/seeds{batch}.zarr``."""
    return f"results/{renderer}/renders/{scene}/{view}/spp{spp}/seeds{batch}.zarr"


AUDIT_PREFIX = "audit/"
"""Source names of audits: ``audit/{name}``."""


def audit_source(name: str) -> str:
    """The source (renderer) name of the audit ``name``: ``audit/{name}``."""
    return f"{AUDIT_PREFIX}{name}"


def is_audit(renderer: str) -> bool:
    """Whether a source name is an audit's (:func:`audit_source`)."""
    return str(renderer).startswith(AUDIT_PREFIX)


def ground_truth_store(renderer: str, scene: str) -> str:
    """Path of a scene's ground truth: ``results/ground_truth/{scene}.zarr``, traced from the
    scene for every renderer, or ``results/audit/{name}/ground_truth/{frame}.zarr``, imported
    with an audit's renders."""
    if is_audit(renderer):
        return f"results/{renderer}/ground_truth/{scene}.zarr"
    return f"results/ground_truth/{scene}.zarr"


def run_prefix(renderer: str, estimator: str) -> str:
    """Directory of everything computed from one renderer's renders by one estimator."""
    return f"results/{renderer}/{estimator}"


def moment_store(renderer: str, scene: str, view: str, spp) -> str:
    """Path of one view's moment store:
    ``results/{renderer}/renders/{scene}/{view}/spp{spp}/moments.zarr``."""
    return f"results/{renderer}/renders/{scene}/{view}/spp{spp}/moments.zarr"


def seed_stores(config: dict, scene: str, spp, n_seeds: int | None = None) -> dict:
    """View to the render stores of seed indices ``0..n_seeds-1`` (``render.n_seeds`` by
    default) of one scene at ``spp``, in ``render.seeds_per_job`` batches."""
    render = config["render"]
    n = int(render["n_seeds"] if n_seeds is None else n_seeds)
    batches = seed_batches(n, int(render["seeds_per_job"]))
    return {
        view: [render_store(render["renderer"], scene, view, spp, batch_label(b)) for b in batches]
        for view in VIEWS
    }


def estimator_stores(config: dict, scene: str, spp, estimator: str | None = None) -> dict:
    """View to the stores ``estimator`` (``render.estimator`` by default) reads for one
    scene at ``spp``: every seed batch (``seeds``) or the one moment store (``moments``)."""
    estimator = estimator or config["render"].get("estimator", "seeds")
    if estimator == "moments":
        renderer = config["render"]["renderer"]
        return {view: [moment_store(renderer, scene, view, spp)] for view in VIEWS}
    return seed_stores(config, scene, spp)


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
