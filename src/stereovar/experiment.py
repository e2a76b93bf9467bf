"""What an experiment config asks for: scene/SPP pairs, seed batches and result paths.

Shared by the workflow's target lists (``workflow/rules/common.smk``) and the benchmarks, so
both enumerate exactly the same renders.
"""

from __future__ import annotations

from .rig import VIEWS

__all__ = ["VIEWS", "render_store", "render_stores", "scene_spp_pairs", "seed_batches"]


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


def render_store(scene: str, view: str, spp, seed) -> str:
    """Path of one render: ``results/renders/{scene}/{view}/spp{spp}/seed{seed}.zarr``."""
    return f"results/renders/{scene}/{view}/spp{spp}/seed{seed}.zarr"


def render_stores(config: dict) -> list[str]:
    """Every render store the config asks for."""
    n = int(config["render"]["n_seeds"])
    return [
        render_store(scene, view, spp, seed)
        for scene, spp in scene_spp_pairs(config)
        for view in VIEWS
        for seed in range(n)
    ]
