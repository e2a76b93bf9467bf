"""Mitigations that act on stored renders: render stores in, render stores out.

:data:`TRANSFORMS` names each :class:`~stereovar.transforms.base.Transform`; its entries are
``"module:attribute"`` strings, so importing this package pulls in neither pyoidn nor the
camera model. The render-time policies (``shared_seed``, ``spp_xK``) act while rendering and
are not store transforms. :mod:`~stereovar.transforms.base` defines the seam (what a
transform reads), :mod:`~stereovar.transforms.registered` the registered objects,
:mod:`~stereovar.transforms.denoise`, :mod:`~stereovar.transforms.sensor` and
:mod:`~stereovar.transforms.output` their work. A chain ``a+b`` applies ``a``, then ``b``
(:func:`transform_chain`): a generator's denoiser, then its PNG.

========================  =============================================================
``denoise``               OIDN on each render, albedo and normal when given (BlenderProc)
``denoise_sensor``        ``denoise``, then Poisson-Gaussian camera noise
``equalise``              the residual rescaled to the camera's variance :math:`a\\mu + b`
``sensor_only``           the seed mean plus camera noise: what a camera would give
``png8_filmic``           Blender's Filmic view transform, 8-bit PNG (Kubric, BlenderProc)
``png16_filmic``          the same at 16 bits (BlenderProc's ``color_depth=16``)
``png8_agx``              Blender's AgX view transform, 8-bit PNG (Infinigen's PNG)
========================  =============================================================
"""

from __future__ import annotations

from ..registry import Registry
from .base import BASE_FIELDS, Transform, TransformInputs, check_reads

TRANSFORMS = Registry("transform", config_key="mitigations.names")
TRANSFORMS.register("denoise", "stereovar.transforms.registered:DENOISE")
TRANSFORMS.register("denoise_sensor", "stereovar.transforms.registered:DENOISE_SENSOR")
TRANSFORMS.register("equalise", "stereovar.transforms.registered:EQUALISE")
TRANSFORMS.register("sensor_only", "stereovar.transforms.registered:SENSOR_ONLY")
TRANSFORMS.register("png8_filmic", "stereovar.transforms.registered:PNG8_FILMIC")
TRANSFORMS.register("png16_filmic", "stereovar.transforms.registered:PNG16_FILMIC")
TRANSFORMS.register("png8_agx", "stereovar.transforms.registered:PNG8_AGX")

CHAIN = "+"
"""Joins the transforms of a chain, applied left to right."""


def get_transform(name: str) -> Transform:
    """The registered transform ``name``.

    Raises
    ------
    stereovar.errors.ConfigError
        ``name`` is not registered (one line listing the registered names).
    """
    return TRANSFORMS.get(name)


def transform_chain(name: str) -> list[Transform]:
    """The registered transforms of ``name``, one or several joined by :data:`CHAIN`, in the
    order they apply.

    Raises
    ------
    stereovar.errors.ConfigError
        A link is not registered (one line listing the registered names).

    Examples
    --------
    >>> [t.name for t in transform_chain("denoise+png8_filmic")]
    ['denoise', 'png8_filmic']
    """
    return [get_transform(part) for part in str(name).split(CHAIN)]


__all__ = [
    "BASE_FIELDS",
    "CHAIN",
    "TRANSFORMS",
    "Transform",
    "TransformInputs",
    "check_reads",
    "get_transform",
    "transform_chain",
]
