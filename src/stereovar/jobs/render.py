"""Job of ``workflow/rules/render.smk``: one batch of seeds of both views of one scene."""

from __future__ import annotations

import time

from ..errors import StereovarError
from .common import log, prepare_scene, render_options


def render_job(
    spec,
    outputs: dict,
    *,
    seeds,
    spp,
    renderer="mitsuba",
    variant="auto",
    seed_policy="independent",
    threads=None,
    **options,
) -> None:
    """Render both views of a scene once per seed index; one render store per view.

    ``outputs`` maps ``left`` and ``right`` to the batch's render stores
    (:mod:`stereovar.io.renders`), each written atomically once its renders are done. The
    sampler seed of each render comes from (scene, view, spp, seed index) under
    ``seed_policy`` (:func:`stereovar.seeding.render_seed`) and is stored with it. ``options``
    hold the rig (``width``, ``height``, ``baseline_m``, ``convention``) and the render
    settings (``integrator``, ``max_depth``, ``rfilter``, ``sampler``). The scene is compiled once
    per job, so the per-render cost is the render itself.
    """
    import numpy as np

    from ..io.contracts import config_digest
    from ..io.renders import render_dataset
    from ..io.store import write_dataset
    from ..rig import VIEWS
    from ..seeding import render_seed

    seeds = [int(s) for s in seeds]
    if sorted(outputs) != sorted(VIEWS):
        raise StereovarError(f"render job needs one output per view {VIEWS}, got {sorted(outputs)}")
    rig, settings = render_options(options)
    prepared = prepare_scene(spec, renderer=renderer, variant=variant, threads=threads, **rig)
    name = prepared.spec["name"]
    stereo = prepared.rig
    determining = {
        "renderer": renderer,
        "width": stereo.width,
        "height": stereo.height,
        "baseline_m": stereo.baseline_m,
        "convention": stereo.convention,
        "spp": int(spp),
        "seed_policy": seed_policy,
        **settings.as_attrs(),
    }
    attrs = {
        **prepared.provenance,
        **determining,
        "config_digest": config_digest(
            {**determining, "scene_digest": prepared.provenance.get("scene_digest")}
        ),
    }
    total = len(VIEWS) * len(seeds)
    done = 0
    for view in VIEWS:
        images, values = [], []
        for index in seeds:
            seed = render_seed(name, view, spp, index, policy=seed_policy)
            start = time.perf_counter()
            image = prepared.render(view, spp=spp, seed=seed, settings=settings)
            elapsed = time.perf_counter() - start
            images.append(image)
            values.append(seed)
            done += 1
            n_bad = int((~np.isfinite(image)).any(axis=-1).sum())
            rate = stereo.width * stereo.height * spp / max(elapsed, 1e-9) / 1e6
            log.info(
                "%s spp %d: %s seed %d (%d/%d) rendered in %.2f s, %.2f Msamples/s%s",
                name,
                spp,
                view,
                index,
                done,
                total,
                elapsed,
                rate,
                f", {n_bad} non-finite pixels" if n_bad else "",
            )
        ds = render_dataset(images, view=view, seeds=seeds, sampler_seeds=values, attrs=attrs)
        write_dataset(ds, outputs[view], chunk_dims={"seed": 1})
