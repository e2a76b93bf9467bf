"""Job of ``workflow/rules/render.smk``: one batch of seeds of both views of one scene."""

from __future__ import annotations

import time
from pathlib import Path

from ..errors import StereovarError
from .common import log, render_options

RENDER_CODE = ("renderers", "scenes", "rig.py", "geometry.py")
"""Modules of :mod:`stereovar` that turn a scene spec into pixels (their source is part of
every render's cache key)."""


def render_code_digest(renderer) -> str:
    """SHA-256 of the code that renders with ``renderer``: :data:`RENDER_CODE` and the module
    defining the renderer's class (:func:`stereovar.io.cache.source_digest`)."""
    import sys

    from .. import __file__ as package_init
    from ..io.cache import source_digest

    package = Path(package_init).parent
    own = Path(sys.modules[type(renderer).__module__].__file__)
    paths = [package / p for p in RENDER_CODE]
    if package not in own.parents:
        paths.append(own)
    return source_digest(paths)


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
    cache=None,
    **options,
) -> None:
    """Render both views of a scene once per seed index; one render store per view.

    ``outputs`` maps ``left`` and ``right`` to the batch's render stores
    (:mod:`stereovar.io.renders`), each written atomically once its renders are done. The
    sampler seed of each render comes from (scene, view, spp, seed index) under
    ``seed_policy`` (:func:`stereovar.seeding.render_seed`) and is stored with it. ``options``
    hold the rig (``width``, ``height``, ``baseline_m``, ``convention``) and the render
    settings (``integrator``, ``max_depth``, ``rfilter``, ``sampler``).

    Each render is also kept in the render cache ``cache`` (:mod:`stereovar.io.cache`; a
    directory, None for none) under the key of everything that determines its pixels. A
    render already there is read instead of rendered, so a batch deleted by a failed or
    changed rerun, or cut short by a kill, costs only the renders that were never finished.
    The back end is resolved and the spec validated before anything is rendered; the scene
    is compiled once per job, and only when a render is missing from the cache.
    """
    import numpy as np

    from ..io.cache import RenderCache, render_key
    from ..io.contracts import config_digest
    from ..io.renders import render_dataset
    from ..io.store import write_dataset
    from ..renderers import get_renderer
    from ..renderers.base import scene_provenance
    from ..rig import VIEWS
    from ..scenes.spec import load_scene_spec
    from ..seeding import render_seed

    seeds = [int(s) for s in seeds]
    if sorted(outputs) != sorted(VIEWS):
        raise StereovarError(f"render job needs one output per view {VIEWS}, got {sorted(outputs)}")
    rig, settings = render_options(options)
    engine = get_renderer(renderer)
    backend = engine.backend(variant)  # an unavailable back end stops here
    scene = load_scene_spec(spec)
    provenance = scene_provenance(scene, backend)
    name = scene["name"]
    determining = {
        "renderer": renderer,
        "width": int(rig["width"]),
        "height": int(rig["height"]),
        "baseline_m": float(rig["baseline_m"]),
        "convention": rig["convention"],
        "spp": int(spp),
        "seed_policy": seed_policy,
        **settings.as_attrs(),
    }
    attrs = {
        **provenance,
        **determining,
        "config_digest": config_digest({**determining, "scene_digest": provenance["scene_digest"]}),
    }
    store = RenderCache(cache) if cache else None
    key_base = {**attrs, "renderer_code": render_code_digest(engine)}
    prepared = None
    total = len(VIEWS) * len(seeds)
    done = rendered = 0
    for view in VIEWS:
        images, values = [], []
        for index in seeds:
            seed = render_seed(name, view, spp, index, policy=seed_policy)
            key = render_key({**key_base, "view": view, "sampler_seed": seed})
            image = store.get(key) if store is not None else None
            done += 1
            if image is not None:
                how = f"from the render cache {store.path(key)}"
            else:
                if prepared is None:
                    prepared = engine.prepare(scene, rig=rig, variant=variant, threads=threads)
                start = time.perf_counter()
                image = prepared.render(view, spp=spp, seed=seed, settings=settings)
                elapsed = time.perf_counter() - start
                rendered += 1
                n_bad = int((~np.isfinite(image)).any(axis=-1).sum())
                rate = rig["width"] * rig["height"] * spp / max(elapsed, 1e-9) / 1e6
                how = f"rendered in {elapsed:.2f} s, {rate:.2f} Msamples/s" + (
                    f", {n_bad} non-finite pixels" if n_bad else ""
                )
                if store is not None:
                    store.put(
                        key,
                        image,
                        {**attrs, "view": view, "seed_index": index, "sampler_seed": seed},
                    )
            log.info("%s spp %d: %s seed %d (%d/%d) %s", name, spp, view, index, done, total, how)
            images.append(image)
            values.append(seed)
        ds = render_dataset(images, view=view, seeds=seeds, sampler_seeds=values, attrs=attrs)
        write_dataset(ds, outputs[view], chunk_dims={"seed": 1})
    log.info(
        "%s spp %d: %d of %d renders rendered, %d from the render cache",
        name,
        spp,
        rendered,
        total,
        total - rendered,
    )
