"""Blender Cycles behind the renderer protocol (:mod:`stereovar.renderers.base`).

:mod:`.backend` loads ``bpy`` (the optional ``cycles`` extra), :mod:`.scene` compiles specs
into a Blender scene with the same geometry as the Mitsuba compiler, :mod:`.settings` sets
and records every render setting (``render.cycles``: the generators' adaptive sampling,
denoiser, multiview and seed rules among them), and :mod:`.render` renders a view, or both
views in one multiview render. The ground truth stays renderer-neutral:
:meth:`CyclesScene.trace` and :meth:`CyclesScene.shape_materials` trace the Mitsuba-compiled
geometry of the same spec, so one ground truth serves both renderers
(:meth:`CyclesScene.geometry` renders Cycles' own planar depth and object index, which the
tests compare with it).

Importing this package pulls in no third-party module; ``bpy`` loads in
:meth:`CyclesRenderer.prepare`.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

from ..base import FirstHits, PreparedScene, Renderer, RenderSettings

log = logging.getLogger("stereovar")

__all__ = ["CyclesRenderer", "CyclesScene"]


@dataclass
class CyclesScene(PreparedScene):
    """A spec compiled into Blender's data, its camera and rig.

    Build one with :meth:`CyclesRenderer.prepare`.
    """

    bpy: Any = None
    camera: Any = None
    threads: int | None = None
    rig_options: dict | None = None
    _mitsuba: Any = None
    _other_eyes: dict = field(default_factory=dict)
    """Multiview renders' eyes not yet asked for, by (view, spp, seed, settings)."""

    _current = None
    """The scene whose data Blender holds: ``bpy`` has one scene per process, so preparing
    another replaces this one's, which is then rebuilt on its next render."""

    def _ensure_built(self) -> None:
        if CyclesScene._current is self:
            return
        from .scene import build_scene

        _, shape_ids = self._geometry().shape_materials()
        self.camera = build_scene(
            self.bpy,
            self.spec,
            width=self.rig.width,
            height=self.rig.height,
            fov_deg=self.rig.fov_deg,
            shape_ids=shape_ids,
        )
        CyclesScene._current = self

    def render(self, view: str, *, spp: int, seed: int, settings: RenderSettings):
        return self.render_with_attrs(view, spp=spp, seed=seed, settings=settings)[0]

    def render_with_attrs(self, view, *, spp, seed, settings: RenderSettings):
        """:meth:`render` plus the Cycles settings used, as store attributes
        (:func:`.render.render_view`).

        Under ``render.cycles.multiview`` one render gives both views
        (:func:`.render.render_pair`): the view asked for is returned and the other kept
        until it is asked for with the same seed, SPP and settings, so a caller asking for
        every view of every seed (views outer, seeds inner, as
        :func:`stereovar.jobs.render.render_job` does) renders each seed once.
        """
        from .settings import cycles_options

        if cycles_options(settings.renderer_options)["multiview"]:
            return self._render_pair_view(view, spp=spp, seed=seed, settings=settings)
        from .render import render_view

        self._ensure_built()
        return render_view(
            self.bpy,
            self.camera,
            self.rig,
            view,
            spp=spp,
            seed=seed,
            max_depth=settings.max_depth,
            threads=self.threads,
            options=settings.renderer_options,
        )

    def _render_pair_view(self, view, *, spp, seed, settings: RenderSettings):
        import json

        from ...rig import VIEWS
        from .render import render_pair

        if view not in VIEWS:
            raise ValueError(f"view must be one of {VIEWS}, got {view!r}")
        same = (int(spp), int(seed), json.dumps(settings.as_attrs(), sort_keys=True))
        kept = self._other_eyes.pop((view, *same), None)
        if kept is not None:
            return kept
        self._ensure_built()
        images, attrs = render_pair(
            self.bpy,
            self.camera,
            self.rig,
            spp=spp,
            seed=seed,
            max_depth=settings.max_depth,
            threads=self.threads,
            options=settings.renderer_options,
        )
        for other in VIEWS:
            if other != view:
                self._other_eyes[(other, *same)] = (images[other], attrs)
        return images[view], attrs

    def geometry(self, view: str) -> dict:
        """Cycles' own planar depth and pass index (shape index + 1) at the pixel centres of
        ``view`` (:func:`.render.render_geometry`), to check against the ground truth."""
        from .render import render_geometry

        self._ensure_built()
        return render_geometry(self.bpy, self.camera, self.rig, view, threads=self.threads)

    def _geometry(self):
        """The same spec compiled by Mitsuba: the renderer-neutral ground truth's geometry."""
        if self._mitsuba is None:
            from ..mitsuba import MitsubaRenderer

            self._mitsuba = MitsubaRenderer().prepare(
                self.spec, rig=self.rig_options, threads=self.threads
            )
        return self._mitsuba

    def trace(self, view: str) -> FirstHits:
        return self._geometry().trace(view)

    def shape_materials(self):
        return self._geometry().shape_materials()


class CyclesRenderer(Renderer):
    """Blender Cycles on the CPU (``render.renderer: cycles``), through ``bpy``."""

    name = "cycles"

    def seed_policy(self, policy: str, options: dict | None = None) -> str:
        """``shared`` under a seed rule that gives both views of a replicate one seed
        (``render.cycles.seed``: :func:`.settings.seed_policy_of`), else ``policy``."""
        from .settings import seed_policy_of

        return seed_policy_of(policy, options)

    def sampler_seed(self, scene: str, view: str, spp, index, *, policy: str, options=None):
        """What Cycles is given under ``render.cycles.seed`` (:func:`.settings.sampler_seed`):
        under ``unset`` and ``animated`` both views of a replicate share one, and
        ``animated`` gives the frame number."""
        from .settings import sampler_seed

        return sampler_seed(scene, view, spp, index, policy=policy, options=options)

    def backend(self, variant: str = "auto") -> dict:
        """Blender's version and build; the device is always the CPU."""
        from .backend import describe_backend

        return describe_backend()

    def prepare(
        self, spec: dict, *, rig: dict, variant: str = "auto", threads: int | None = None
    ) -> CyclesScene:
        """Load ``bpy``, compile ``spec`` and build the rig (see
        :meth:`stereovar.renderers.base.Renderer.prepare`). ``variant`` is ignored: Cycles
        renders on the CPU."""
        from ...rig import make_rig
        from ..base import scene_provenance
        from ..mitsuba import MitsubaRenderer
        from ..mitsuba.scene import camera_from_spec
        from .backend import load_bpy

        bpy = load_bpy()
        camera = camera_from_spec(spec)
        stereo = make_rig(camera.to_world, camera.fov_deg, **rig)
        geometry = MitsubaRenderer().prepare(spec, rig=rig, threads=threads)
        provenance = scene_provenance(spec, self.backend(variant))
        log.info(
            "scene %s: %s %s, %dx%d, baseline %.4f m, convention %s",
            spec["name"],
            self.name,
            provenance["renderer_version"],
            stereo.width,
            stereo.height,
            stereo.baseline_m,
            stereo.convention,
        )
        prepared = CyclesScene(
            stereo,
            spec=spec,
            provenance=provenance,
            bpy=bpy,
            threads=threads,
            rig_options=dict(rig),
            _mitsuba=geometry,
        )
        prepared._ensure_built()  # a spec Cycles cannot compile stops here
        return prepared


RENDERER = CyclesRenderer
"""The class :data:`stereovar.renderers.RENDERERS` builds for ``render.renderer: cycles``."""
