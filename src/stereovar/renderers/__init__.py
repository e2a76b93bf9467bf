"""Renderers behind one protocol (:mod:`stereovar.renderers.base`), selected by
``render.renderer``.

:data:`RENDERERS` maps each name to its :class:`~stereovar.renderers.base.Renderer` class,
imported on first use; :func:`get_renderer` builds one. A new renderer is a subpackage of
``stereovar.renderers`` plus one :meth:`~stereovar.registry.Registry.register` call below and
the name in the config schema's ``render.renderer`` enum.
"""

from __future__ import annotations

from ..registry import Registry, factory

RENDERERS = Registry("renderer", config_key="render.renderer")
RENDERERS.register("mitsuba", "stereovar.renderers.mitsuba:MitsubaRenderer")

get_renderer = factory(RENDERERS)
"""``get_renderer(name, **options)``: a :class:`~stereovar.renderers.base.Renderer`."""

__all__ = ["RENDERERS", "get_renderer"]
