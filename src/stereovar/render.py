"""Path-traced renders of one view of the rig with an explicit, reproducible seed."""

from __future__ import annotations

import hashlib

import numpy as np

from .rig import StereoRig, sensor_dict


def derive_seed(*parts) -> int:
    """Deterministic 32-bit sampler seed from labelled parts (scene, view, spp, index, ...).

    Mitsuba gives two sensors rendered with the same seed identical random streams, so each
    view must get its own seed; hashing the parts gives distinct, reproducible values.

    .. math:: \\mathrm{seed} = \\mathrm{SHA256}(p_1 \\,|\\, p_2 \\,|\\, \\dots)\\ \\bmod\\ 2^{32}
    """
    text = "|".join(str(p) for p in parts).encode()
    return int.from_bytes(hashlib.sha256(text).digest()[:4], "little")


def integrator_dict(kind: str = "path", max_depth: int = 8) -> dict:
    """Mitsuba integrator dict (``path`` with the given ``max_depth``; -1 is unbounded)."""
    return {"type": kind, "max_depth": int(max_depth)}


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
        Sampler seed passed to ``mi.render`` (use :func:`derive_seed`).
    integrator : dict, optional
        Mitsuba integrator dict; default :func:`integrator_dict`.
    rfilter, sampler : str
        Reconstruction filter and sampler plugin names.

    Returns
    -------
    numpy.ndarray, shape (height, width, 3), float32
        Linear RGB radiance.
    """
    sensor = mi.load_dict(sensor_dict(mi, rig, view, spp=spp, rfilter=rfilter, sampler=sampler))
    integ = mi.load_dict(integrator or integrator_dict())
    image = mi.render(scene, sensor=sensor, integrator=integ, seed=int(seed), spp=int(spp))
    return np.asarray(image, dtype=np.float32)[..., :3]
