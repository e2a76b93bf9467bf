"""Mitigations that act on stored renders: render stores in, render stores out.

:data:`TRANSFORMS` names each :class:`~stereovar.transforms.base.Transform`; its entries are
``"module:attribute"`` strings, so importing this package pulls in neither pyoidn nor the
camera model. The render-time policies (``shared_seed``, ``spp_xK``) act while rendering and
are not store transforms. :mod:`~stereovar.transforms.base` defines the seam (what a
transform reads), :mod:`~stereovar.transforms.registered` the registered objects,
:mod:`~stereovar.transforms.denoise` and :mod:`~stereovar.transforms.sensor` their work.

========================  =============================================================
``denoise``               OIDN on each render, albedo and normal when given (BlenderProc)
``denoise_sensor``        ``denoise``, then Poisson-Gaussian camera noise
``equalise``              the residual rescaled to the camera's variance :math:`a\\mu + b`
``sensor_only``           the seed mean plus camera noise: what a camera would give
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


def get_transform(name: str) -> Transform:
    """The registered transform ``name``.

    Raises
    ------
    stereovar.errors.ConfigError
        ``name`` is not registered (one line listing the registered names).
    """
    return TRANSFORMS.get(name)


__all__ = [
    "BASE_FIELDS",
    "TRANSFORMS",
    "Transform",
    "TransformInputs",
    "check_reads",
    "get_transform",
]
