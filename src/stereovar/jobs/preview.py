"""Job of ``workflow/rules/preview.smk``: both views at a modest SPP, disparity and materials."""

from __future__ import annotations

import time

from .common import RIG_KEYS, log, prepare_scene, render_options, save_figure


def preview_job(
    spec,
    ground_truth,
    out,
    *,
    spp,
    renderer="mitsuba",
    variant="auto",
    seed_policy="independent",
    threads=None,
    **settings,
) -> None:
    """Render both views at ``spp`` and save the preview figure as PNG.

    ``settings`` are the render settings (``integrator``, ``max_depth``, ``rfilter``,
    ``sampler``; :class:`~stereovar.renderers.base.RenderSettings`); the rig comes from the
    ground truth's attrs.
    """
    import matplotlib

    matplotlib.use("Agg")

    from ..figures.preview import preview_figure
    from ..io.store import load_store
    from ..rig import VIEWS
    from ..seeding import render_seed

    gt = load_store(ground_truth, "ground-truth store")
    prepared = prepare_scene(
        spec,
        renderer=renderer,
        variant=variant,
        threads=threads,
        **{k: gt.attrs[k] for k in RIG_KEYS},
    )
    _, settings = render_options(settings)
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
