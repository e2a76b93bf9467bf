"""Renderers behind one protocol (:mod:`stereovar.renderers.base`), selected by
``render.renderer``.

Every subpackage of ``stereovar.renderers`` is a renderer: its name is the config value and
its ``RENDERER`` attribute the :class:`~stereovar.renderers.base.Renderer` class, imported on
first use. :data:`RENDERERS` lists them; :func:`get_renderer` builds one. A new renderer is
one new subpackage plus its name in the config schema's ``render.renderer`` enum; a test or
notebook can also :meth:`~stereovar.registry.Registry.register` one of its own.

``base``
    The protocol: :class:`~stereovar.renderers.base.Renderer`, a prepared scene, first hits.
``mitsuba``
    Mitsuba 3 (CUDA, LLVM or scalar variants); the Mitsuba-only functions live here.
``cycles``
    Blender Cycles on the CPU, through ``bpy``.
``quiet``
    Silencing a C-level file descriptor while native code prints (standard library only).
"""

from __future__ import annotations

import pkgutil

from ..registry import Registry, factory

RENDERERS = Registry("renderer", config_key="render.renderer")
for _info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
    if _info.ispkg:
        RENDERERS.register(_info.name, f"{__name__}.{_info.name}:RENDERER")

get_renderer = factory(RENDERERS)
"""``get_renderer(name, **options)``: a :class:`~stereovar.renderers.base.Renderer`."""

__all__ = ["RENDERERS", "get_renderer"]
