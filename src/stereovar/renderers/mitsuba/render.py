"""Path-traced renders of one view of the rig with an explicit, reproducible seed."""

from __future__ import annotations

import numpy as np

from ...rig import StereoRig
from .sensor import integrator_dict, sensor_dict


def render_view(
    mi,
    scene,
    rig: StereoRig,
    view: str,
    *,
    spp: int,
    seed: int,
    integrator: dict | None = None,
    rfilter: str = "box",
    sampler: str = "independent",
    channels: int | None = 3,
) -> np.ndarray:
    """Render one view of the rig.

    Parameters
    ----------
    mi : module
        ``mitsuba`` with a variant set.
    scene : mitsuba.Scene
    rig : StereoRig
    view : {"left", "right"}
    spp : int
        Samples per pixel.
    seed : int
        Sampler seed passed to ``mi.render`` (use :func:`stereovar.seeding.render_seed`).
    integrator : dict, optional
        Mitsuba integrator dict; default :func:`integrator_dict`.
    rfilter, sampler : str
        Reconstruction filter and sampler plugin names.
    channels : int or None
        Leading channels returned (3: linear RGB); None returns every channel of the film
        (RGB followed by the integrator's AOVs).

    Returns
    -------
    numpy.ndarray, shape (height, width, channels), float32
        Linear RGB radiance (and AOVs).
    """
    sensor = mi.load_dict(sensor_dict(mi, rig, view, spp=spp, rfilter=rfilter, sampler=sampler))
    integ = mi.load_dict(integrator or integrator_dict())
    image = mi.render(scene, sensor=sensor, integrator=integ, seed=int(seed), spp=int(spp))
    return np.asarray(image, dtype=np.float32)[..., :channels]
