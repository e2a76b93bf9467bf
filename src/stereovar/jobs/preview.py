"""Job of ``workflow/rules/preview.smk``: both views at a modest SPP, disparity and materials."""

from __future__ import annotations

import time

from .common import log, prepare_scene, save_figure


def preview_job(
    spec,
    ground_truth,
    out,
    *,
    renderer="mitsuba",
    variant="auto",
    spp,
    integrator="path",
    max_depth=8,
    rfilter="box",
    sampler="independent",
    seed_policy="independent",
    threads=None,
) -> None:
    """Render both views at ``spp`` and save the preview figure as PNG."""
    import matplotlib

    matplotlib.use("Agg")

    from ..figures.preview import preview_figure
    from ..io.store import open_dataset
    from ..renderers.base import RenderSettings
    from ..rig import VIEWS
    from ..seeding import render_seed

    gt = open_dataset(ground_truth).load()
    prepared = prepare_scene(
        spec,
        renderer=renderer,
        variant=variant,
        width=int(gt.attrs["width"]),
        height=int(gt.attrs["height"]),
        baseline_m=float(gt.attrs["baseline_m"]),
        convention=str(gt.attrs["convention"]),
        threads=threads,
    )
    settings = RenderSettings(integrator, max_depth, rfilter, sampler)
    name = prepared.spec["name"]
    images = {}
    for view in VIEWS:
        start = time.perf_counter()
        images[view] = prepared.render(
            view,
            spp=spp,
            seed=render_seed(name, view, spp, "preview", policy=seed_policy),
            settings=settings,
        )
        log.info("rendered %s view at %d spp in %.2f s", view, spp, time.perf_counter() - start)
    fig = preview_figure(images["left"], images["right"], gt, title=f"{name} ({renderer})", spp=spp)
    save_figure(fig, out, dpi=110)
