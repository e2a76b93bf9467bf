"""A seed-mean mitigation's dose-response: the Monte Carlo-specific :math:`\\rho` of what it
ships, predicted over the budget behind one shipped image and the camera's law, and measured
on renders where the run has them.

A transform that builds its image from the seed mean (``sensor_only``, ``equalise``) ships
the mean of :math:`k` renders at :math:`s` samples per pixel with camera noise: the image's
variance is

.. math::

    V_S(x) = \\frac{\\sigma^2_{s}(x)\\, s}{S} + a\\,\\mu(x) + b, \\qquad S = k\\,s,

with :math:`\\sigma^2_s` the renders' Eq. 1 field at :math:`s` SPP (its :math:`1/\\mathrm{SPP}`
law, paper Fig. 2 and the SPP sweep), :math:`S` the samples behind one shipped image and
:math:`(a, b)` the camera's law (:func:`stereovar.transforms.sensor.camera_coefficients`).
The Monte Carlo part, the one that carries the cross-view cue, falls as :math:`1/S` against a
camera term that does not.

**Prediction.** For each budget multiple :math:`m` (``multiples``, :math:`S = m\\,k\\,s`) and
camera, :math:`N` frames per view are drawn around the seed mean with the renders' own
variance field over :math:`m` (their cue included) and passed through what the transform
ships over disjoint groups of :math:`k = 2` (:func:`~stereovar.calibration.stacks.
shipped_stack`, as the mitigation table measures it); the intensity-controlled :math:`\\rho`
of the :math:`G = N/k` shipped images is read against the same statistic on the matched
null, camera-law noise at the renders' level over :math:`m` through the same path
(:func:`~stereovar.calibration.nulls.difference_interval`).

**Verification.** Where the run has renders at :math:`m\\,s` SPP (``spp_xK``: the renders at
K times the SPP), the same path on those renders against the same null.

The verdict at each point is :func:`stereovar.statistics.mitigations.mc_cue_state` against
the transform's equivalence margin on what it ships (the calibration's), and the budget that
removes the cue is the smallest :math:`S` whose predicted interval reads ``removed``.
"""

from __future__ import annotations

import numpy as np

from ..seeding import derive_seed
from .scene_frames import SceneFrames
from .stacks import SHIPPED, seed_groups, shipped_stack
from .synthesis import camera_law, draw_frames
from .view_statistics import statistic_rows

MULTIPLES = (1, 2, 4, 8, 16, 32, 64)
"""Budget multiples of the measured shipped image (2 renders at the run's SPP) predicted."""

GROUP = 2
"""Renders per shipped image in the measurement (:func:`~stereovar.calibration.stacks.
seed_groups`)."""

DOSE_COLUMNS = [
    "scene",
    "transform",
    "gain",
    "read_noise",
    "multiple",
    "shipped_spp",
    "kind",
    "replicate",
    "rho",
    "boot_low",
    "boot_high",
    "chance_se",
    "mse",
]
"""Columns of one scene's dose-response rows: ``kind`` ``predicted`` (synthetic frames with the
renders' field over the multiple), ``null`` (camera-law frames through the same path) or
``renders`` (the run's renders at that multiple); ``rho`` the intensity-controlled
:math:`\\rho` of what ships; ``mse`` the shipped image's mean variance over the valid pixels
(its error against the clean image: the transforms are unbiased)."""


def dose_rows(
    scene: SceneFrames,
    *,
    transform: str,
    cameras,
    settings,
    multiples=MULTIPLES,
    replicates: int = 4,
    renders: dict | None = None,
    seed: int = 0,
) -> list[dict]:
    """One scene's dose-response rows (:data:`DOSE_COLUMNS` but ``scene``).

    Parameters
    ----------
    scene : SceneFrames
        The renders' seed mean and Eq. 1 field at the run's SPP :math:`s`, :math:`N` frames.
    transform : str
        A transform that reads the seed mean.
    cameras : sequence of dict
        Each ``{"gain", "read_noise"}``: the camera the transform adds.
    multiples : sequence of int
        Budget multiples :math:`m` to predict.
    replicates : int
        Replicates of each predicted point and of its null.
    renders : dict, optional
        Multiple to ``{view: frames (N, H, W, C)}``: renders at :math:`m\\,s` SPP to verify
        with.
    """
    if not seed_groups(scene.n_seeds, GROUP):
        raise ValueError(f"the dose-response needs N >= {2 * GROUP} renders per view")
    mu = {v: np.asarray(m, dtype=np.float64).mean(axis=-1) for v, m in scene.mean.items()}
    valid = np.asarray(scene.ground_truth["left"]["valid"], dtype=bool)
    a, b = camera_law(scene.variance["left"], mu["left"], valid)
    spp = int(scene.label.rsplit("spp", 1)[-1]) if "spp" in scene.label else 0
    rows = []

    def measure(frames, camera, kind, m, r, label):
        options = {"gain": float(camera["gain"]), "read_noise": float(camera["read_noise"])}
        stacks = {
            view: shipped_stack(transform, frames[view], view=view,
                                seed=derive_seed(label, view), options=options, size=GROUP)
            for view in ("left", "right")
        }
        (row,) = statistic_rows(stacks, scene, settings, label, methods=("partial",))
        variance = np.var(np.asarray(stacks["left"], dtype=np.float64), axis=0, ddof=1)
        rows.append({
            "transform": transform, "gain": options["gain"],
            "read_noise": options["read_noise"], "multiple": int(m),
            "shipped_spp": int(m * GROUP * spp), "kind": kind, "replicate": int(r),
            "rho": row["rho"], "boot_low": row["boot_low"], "boot_high": row["boot_high"],
            "chance_se": row["chance_se"],
            "mse": float(np.nanmean(variance.mean(axis=-1)[valid])),
        })

    for camera in cameras:
        for m in multiples:
            for r in range(int(replicates)):
                label = f"{scene.label}|dose|{transform}|{camera['gain']}|{m}|{r}"
                rng = np.random.default_rng(derive_seed("dose", seed, label))
                for kind in ("predicted", "null"):
                    frames = {}
                    for view, clean in scene.mean.items():
                        v = (np.asarray(scene.variance[view], dtype=np.float64)
                             if kind == "predicted" else a * mu[view] + b)
                        frames[view] = draw_frames(
                            clean, np.maximum(v, 0.0) / m, scene.n_seeds, rng,
                            channel_correlation=scene.channel_correlation)
                    measure(frames, camera, kind, m, r, f"{label}|{kind}")
            if renders and m in renders:
                measure(renders[m], camera, "renders", m, 0,
                        f"{scene.label}|dose|{transform}|{camera['gain']}|{m}|renders")
    return rows


__all__ = ["DOSE_COLUMNS", "GROUP", "MULTIPLES", "SHIPPED", "dose_rows"]
