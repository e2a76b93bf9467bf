"""Mitsuba 3 behind the renderer protocol (:mod:`stereovar.renderers.base`).

:mod:`.backend` picks the variant, :mod:`.scene` compiles specs, :mod:`.sensor` builds the rig's
sensors, :mod:`.render` renders a view and :mod:`.trace` intersects pixel-centre rays. Only
this subpackage imports ``mitsuba`` or ``drjit`` (through :func:`.backend.load_mitsuba`).

Importing this package pulls in no third-party module; the back end loads in
:meth:`MitsubaRenderer.prepare`.

The Mitsuba-only functions are importable from here, each loaded from its module on first
use: :func:`~.backend.load_mitsuba` and :func:`~.backend.select_variant` (the variant),
:func:`~.scene.load_scene` (a spec compiled into a Mitsuba scene and its camera) and
:func:`~.render.render_view` (one view of the rig rendered). The modules :mod:`.jit_target`
(Dr.Jit's LLVM target) and :mod:`.moments` (per-pixel sample moments of one render) serve the
back end and the ``moments`` estimator.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..base import FirstHits, PreparedScene, Renderer, RenderSettings

if TYPE_CHECKING:  # for type checkers and editors; at run time, __getattr__ imports them
    from .backend import load_mitsuba, select_variant
    from .render import render_view
    from .scene import load_scene

log = logging.getLogger("stereovar")

_LAZY = {
    "load_mitsuba": "backend",
    "select_variant": "backend",
    "load_scene": "scene",
    "render_view": "render",
}
"""Functions of the submodules, imported on first access (:func:`__getattr__`) so that this
package stays free of numpy."""

__all__ = [
    "MitsubaRenderer",
    "MitsubaScene",
    "load_mitsuba",
    "load_scene",
    "render_view",
    "select_variant",
]


def __getattr__(name: str):
    if name in _LAZY:
        from importlib import import_module

        return getattr(import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


@dataclass
class MitsubaScene(PreparedScene):
    """A compiled Mitsuba scene and its rig.

    Build one with :meth:`MitsubaRenderer.prepare`, or directly from a loaded scene:
    ``MitsubaScene(rig, mi=mi, scene=scene)``.
    """

    mi: Any = None
    scene: Any = None

    def _render(
        self, view, spp, seed, settings: RenderSettings, wrap=None, channels=3, integrator=None
    ):
        """``render_view`` with the settings' integrator (wrapped by ``wrap`` when given), or
        with ``integrator`` instead, and the settings' filter and sampler."""
        from .render import render_view
        from .sensor import integrator_dict

        if integrator is None:
            integrator = integrator_dict(settings.integrator, settings.max_depth)
        return render_view(
            self.mi,
            self.scene,
            self.rig,
            view,
            spp=spp,
            seed=seed,
            integrator=wrap(integrator) if wrap else integrator,
            rfilter=settings.rfilter,
            sampler=settings.sampler,
            channels=channels,
        )

    def render(self, view: str, *, spp: int, seed: int, settings: RenderSettings):
        return self._render(view, spp, seed, settings)

    def render_moments(self, view: str, *, spp: int, seed: int, settings: RenderSettings):
        """One render of ``view`` through :mod:`.moments`: its per-pixel sample moments."""
        from .moments import film_moments, moment_integrator_dict, register

        register(self.mi)
        image = self._render(view, spp, seed, settings, wrap=moment_integrator_dict, channels=None)
        return film_moments(image, spp)

    def render_aux(self, view: str, *, spp: int, seed: int):
        """Albedo and shading normal of ``view`` from Mitsuba's ``aov`` integrator alone (a
        separate cheap pass: wrapping ``path`` in ``aov`` would cost 3-4x every render), with
        the box filter and the independent sampler (the default settings)."""
        aov = {"type": "aov", "aovs": "albedo:albedo,normal:sh_normal"}
        image = self._render(view, spp, seed, RenderSettings(), channels=None, integrator=aov)
        return image[..., 0:3], image[..., 3:6]

    def trace(self, view: str) -> FirstHits:
        from .sensor import sensor_dict
        from .trace import trace_pixel_centres

        sensor = self.mi.load_dict(sensor_dict(self.mi, self.rig, view))
        return FirstHits(
            *trace_pixel_centres(self.mi, self.scene, sensor, self.rig.width, self.rig.height)
        )

    def shape_materials(self):
        from .trace import shape_classes

        return shape_classes(self.mi, self.scene)


class MitsubaRenderer(Renderer):
    """Mitsuba 3 (``render.renderer: mitsuba``): CUDA, LLVM or scalar variants."""

    name = "mitsuba"
    sample_moments = True
    aux_passes = ("albedo", "normal")

    def backend(self, variant: str = "auto") -> dict:
        """Mitsuba's version, Dr.Jit's and the variant ``variant`` resolves to here
        (:func:`.backend.select_variant`)."""
        from .backend import describe_backend, load_mitsuba

        load_mitsuba(variant)
        info = describe_backend()
        return {
            "renderer": self.name,
            "renderer_version": info["mitsuba_version"],
            "drjit_version": info["drjit_version"],
            "variant": info["variant"],
            "jit_target": info["jit_target"],
        }

    def prepare(
        self, spec: dict, *, rig: dict, variant: str = "auto", threads: int | None = None
    ) -> MitsubaScene:
        """Load the back end, compile ``spec`` and build the rig (see
        :meth:`stereovar.renderers.base.Renderer.prepare`)."""
        from ...rig import make_rig
        from ..base import scene_provenance
        from .backend import load_mitsuba
        from .scene import load_scene

        mi = load_mitsuba(variant)
        if threads:
            import drjit as dr

            dr.set_thread_count(int(threads))
        scene, camera = load_scene(mi, spec)
        stereo = make_rig(camera.to_world, camera.fov_deg, **rig)
        provenance = scene_provenance(spec, self.backend(variant))
        log.info(
            "scene %s: %s %s, %dx%d, baseline %.4f m, convention %s",
            spec["name"],
            self.name,
            provenance["variant"],
            stereo.width,
            stereo.height,
            stereo.baseline_m,
            stereo.convention,
        )
        return MitsubaScene(stereo, spec=spec, provenance=provenance, mi=mi, scene=scene)


RENDERER = MitsubaRenderer
"""The class :data:`stereovar.renderers.RENDERERS` builds for ``render.renderer: mitsuba``."""
