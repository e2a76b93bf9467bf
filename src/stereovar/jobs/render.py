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


class _Job:
    """What every render of one job shares: the renderer, its back end, the spec, the
    provenance attrs, the render-cache key base and the scene (compiled on first use)."""

    def __init__(
        self, spec, *, spp, renderer, variant, seed_policy, threads, cache, options
    ) -> None:
        from ..io.cache import RenderCache
        from ..io.contracts import config_digest
        from ..renderers import get_renderer
        from ..renderers.base import scene_provenance
        from ..scenes.spec import load_scene_spec

        self.rig, self.settings = render_options(options)
        self.engine = get_renderer(renderer)
        backend = self.engine.backend(variant)  # an unavailable back end stops here
        self.spec = load_scene_spec(spec)
        provenance = scene_provenance(self.spec, backend)
        self.name = self.spec["name"]
        self.spp, self.variant, self.threads = int(spp), variant, threads
        # a renderer's own seed rule (Cycles' render.cycles.seed) may share the views' seeds
        seed_policy = self.engine.seed_policy(seed_policy, self.settings.renderer_options)
        self.seed_policy = seed_policy
        determining = {
            "renderer": renderer,
            "width": int(self.rig["width"]),
            "height": int(self.rig["height"]),
            "baseline_m": float(self.rig["baseline_m"]),
            "convention": self.rig["convention"],
            "spp": self.spp,
            "seed_policy": seed_policy,
            **self.settings.as_attrs(),
        }
        self.attrs = {
            **provenance,
            **determining,
            "config_digest": config_digest(
                {**determining, "scene_digest": provenance["scene_digest"]}
            ),
        }
        self.cache = RenderCache(cache) if cache else None
        self.key_base = {**self.attrs, "renderer_code": render_code_digest(self.engine)}
        self.rendered = 0
        self._prepared = None

    @property
    def prepared(self):
        """The compiled scene (compiled on first use, once per job)."""
        if self._prepared is None:
            self._prepared = self.engine.prepare(
                self.spec, rig=self.rig, variant=self.variant, threads=self.threads
            )
        return self._prepared

    def seed(self, view: str, index) -> int:
        """The sampler seed of render ``index`` of ``view``, as the renderer takes it
        (:meth:`stereovar.renderers.base.Renderer.sampler_seed`)."""
        return self.engine.sampler_seed(
            self.name,
            view,
            self.spp,
            index,
            policy=self.seed_policy,
            options=self.settings.renderer_options,
        )

    def get_or_render(self, view: str, index, render, *, spp=None, extra=None, channels=None):
        """The cached array of one render, or ``render(seed)``'s, then cached.

        Returns ``(array, sampler seed, how)`` with ``how`` a phrase for the log.
        """
        import numpy as np

        from ..io.cache import render_key

        seed = self.seed(view, index)
        key = render_key({**self.key_base, **(extra or {}), "view": view, "sampler_seed": seed})
        array = self.cache.get(key) if self.cache is not None else None
        if array is not None:
            return array, seed, f"from the render cache {self.cache.path(key)}"
        start = time.perf_counter()
        array = render(seed)
        elapsed = time.perf_counter() - start
        self.rendered += 1
        n_bad = int((~np.isfinite(array)).any(axis=-1).sum())
        samples = self.rig["width"] * self.rig["height"] * int(spp or self.spp)
        how = f"rendered in {elapsed:.2f} s, {samples / max(elapsed, 1e-9) / 1e6:.2f} Msamples/s"
        if n_bad:
            how += f", {n_bad} non-finite pixels"
        if self.cache is not None:
            self.cache.put(
                key,
                array,
                {
                    **self.attrs,
                    **(extra or {}),
                    "view": view,
                    "seed_index": index,
                    "sampler_seed": seed,
                },
                channels=channels,
            )
        return array, seed, how


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
    from ..io.renders import render_dataset
    from ..io.store import write_dataset
    from ..rig import VIEWS

    seeds = [int(s) for s in seeds]
    if sorted(outputs) != sorted(VIEWS):
        raise StereovarError(f"render job needs one output per view {VIEWS}, got {sorted(outputs)}")
    job = _Job(
        spec,
        spp=spp,
        renderer=renderer,
        variant=variant,
        seed_policy=seed_policy,
        threads=threads,
        cache=cache,
        options=options,
    )
    total = len(VIEWS) * len(seeds)
    done = 0
    for view in VIEWS:
        images, values = [], []
        for index in seeds:
            image, seed, how = job.get_or_render(
                view,
                index,
                lambda s, view=view: job.prepared.render(
                    view, spp=job.spp, seed=s, settings=job.settings
                ),
            )
            done += 1
            log.info(
                "%s spp %d: %s seed %d (%d/%d) %s", job.name, job.spp, view, index, done, total, how
            )
            images.append(image)
            values.append(seed)
        ds = render_dataset(images, view=view, seeds=seeds, sampler_seeds=values, attrs=job.attrs)
        write_dataset(ds, outputs[view], chunk_dims={"seed": 1})
    log.info(
        "%s spp %d: %d of %d renders rendered, %d from the render cache",
        job.name,
        job.spp,
        job.rendered,
        total,
        total - job.rendered,
    )


MOMENT_HALVES = 2
"""Independent half renders per view of the ``moments`` estimator."""


def half_spp(spp: int, halves: int = MOMENT_HALVES) -> list[int]:
    """Samples per pixel of each half render: ``spp`` split as evenly as possible."""
    spp = int(spp)
    if spp < 2 * halves:
        raise StereovarError(
            f"the moments estimator needs spp >= {2 * halves} (two samples per half render), "
            f"got {spp}"
        )
    return [spp // halves + (1 if h < spp % halves else 0) for h in range(halves)]


def moments_job(
    spec,
    out,
    *,
    view,
    spp,
    renderer="mitsuba",
    variant="auto",
    seed_policy="independent",
    threads=None,
    cache=None,
    **options,
) -> None:
    """Render one view of a scene for the ``moments`` estimator; one moment store.

    The SPP is rendered as :data:`MOMENT_HALVES` independent half renders (:func:`half_spp`),
    each with its own sampler seed (seed index ``moments0``, ``moments1`` under
    ``seed_policy``, so never one of the ``seeds`` estimator's), through the renderer's
    per-sample moments (:meth:`stereovar.renderers.base.PreparedScene.render_moments`). The
    store (:mod:`stereovar.io.moments`) is written atomically once both halves are done;
    each half is kept in the render cache like a render of :func:`render_job`.
    """
    from ..io.moments import moments_dataset
    from ..io.store import write_dataset
    from ..renderers.base import SampleMoments

    job = _Job(
        spec,
        spp=spp,
        renderer=renderer,
        variant=variant,
        seed_policy=seed_policy,
        threads=threads,
        cache=cache,
        options=options,
    )
    from ..config import moments_settings_error
    from ..errors import ConfigError

    error = moments_settings_error(job.settings.sampler, job.settings.rfilter)
    if error:
        raise ConfigError(error)
    counts = half_spp(job.spp)
    halves, seeds = [], []
    for h, n in enumerate(counts):
        array, seed, how = job.get_or_render(
            view,
            f"moments{h}",
            lambda s, n=n: job.prepared.render_moments(
                view, spp=n, seed=s, settings=job.settings
            ).stack(),
            spp=n,
            extra={"estimator": "moments", "half_spp": n},
            channels=SampleMoments.CHANNELS,
        )
        log.info("%s spp %d: %s half render %d (spp %d) %s", job.name, job.spp, view, h, n, how)
        halves.append(SampleMoments.from_stack(array))
        seeds.append(seed)
    ds = moments_dataset(
        halves,
        view=view,
        sampler_seeds=seeds,
        half_spp=counts,
        attrs={**job.attrs, "estimator": "moments"},
    )
    write_dataset(ds, out)
    n_bad = int(job.spp * ds.sizes["y"] * ds.sizes["x"] - ds["n_samples"].sum())
    log.info(
        "%s spp %d: %s moments of %d half renders (%d rendered, %d from the render cache); "
        "%d non-finite samples",
        job.name,
        job.spp,
        view,
        len(counts),
        job.rendered,
        len(counts) - job.rendered,
        n_bad,
    )
