"""Mitsuba sensor and integrator dicts for the views of the stereo rig."""

from __future__ import annotations

from ...rig import StereoRig


def integrator_dict(kind: str = "path", max_depth: int = 8) -> dict:
    """Mitsuba integrator dict (``path`` with the given ``max_depth``; -1 is unbounded)."""
    return {"type": kind, "max_depth": int(max_depth)}


def sensor_dict(
    mi,
    rig: StereoRig,
    view: str,
    *,
    spp: int = 1,
    rfilter: str = "box",
    sampler: str = "independent",
) -> dict:
    """Mitsuba ``perspective`` sensor dict for one view of the rig.

    The film stores linear float32 RGB with the given reconstruction filter (``box`` by
    default, so a pixel's variance is that pixel's own estimator variance).
    """
    return {
        "type": "perspective",
        "fov": rig.fov_deg,
        "fov_axis": "x",
        "near_clip": 1e-3,
        "far_clip": 1e4,
        "to_world": mi.ScalarTransform4f(rig.to_world[view].tolist()),
        "film": {
            "type": "hdrfilm",
            "width": rig.width,
            "height": rig.height,
            "rfilter": {"type": rfilter},
            "pixel_format": "rgb",
            "component_format": "float32",
        },
        "sampler": {"type": sampler, "sample_count": int(spp)},
    }
