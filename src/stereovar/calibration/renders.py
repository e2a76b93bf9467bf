"""The run's own renders measured as the calibration measures its designs: what each
transform that reads the seed mean ships (:func:`renders_shipped_rows`) and what a generator
ships (:func:`renders_output_rows`), as rows of kind ``renders`` beside the replicates.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..seeding import derive_seed
from .scene_frames import SceneFrames
from .stacks import output_encoding_of, reads_seed_mean, transform_stack
from .view_statistics import measured_rows, statistic_rows

QUANTISED_SHARE = "quantised_share"
"""The ``method`` of a shipped output's row whose ``rho`` is the share of valid pixels whose
Eq. 1 variance the output's integer encoding fixes
(:func:`stereovar.controls.quantisation.fixed_share`, the larger of the two views)."""


def renders_shipped_rows(renders: dict, scene: SceneFrames, *, transforms, settings,
                         options=None, seed: int = 0) -> list[dict]:
    """What each transform that reads the seed mean ships, measured on the run's own renders
    (:func:`~stereovar.calibration.stacks.shipped_stack` over disjoint seed groups;
    ``kind`` ``renders``)."""
    options = dict(options or {})
    rows = []
    for name in transforms:
        if not reads_seed_mean(name):
            continue
        rows += measured_rows(
            renders, name, scene, settings,
            label=f"{scene.label}|renders|{name}",
            seed=derive_seed("calibration-renders", seed, scene.label, name),
            options=options.get(name),
            design={"replicate": 0, "kind": "renders", "strength": float("nan"),
                    "strength_factor": float("nan")},
            shipped_only=True,
        )
    return rows


def renders_output_rows(renders: dict, scene: SceneFrames, *, outputs: dict, settings,
                        seed: int = 0) -> list[dict]:
    """What a generator ships, measured on its own renders (``kind`` ``renders``), and the
    share of pixels whose variance its encoding fixes (method :data:`QUANTISED_SHARE`).

    Parameters
    ----------
    renders : dict
        View to the generator's renders (N, H, W, C), its own denoiser already applied.
    outputs : dict
        Label to the transform its renders pass through before they ship (its PNG writer,
        :mod:`stereovar.transforms.output`). The label is the chain its matched null passes
        through (``denoise+png8_filmic``: the null is drawn at the raw renders' level, so it
        also passes the denoiser the renderer ran), and the rows carry it, so that
        :func:`stereovar.statistics.matched_null.matched_difference` pairs them with that
        null.
    """
    from ..controls.quantisation import fixed_share, quantisation_variance
    from ..estimators.seeds import variance_field

    design = {"replicate": 0, "kind": "renders", "strength": float("nan"),
              "strength_factor": float("nan"), "null_kind": "camera"}
    rows = []
    for label, ship in outputs.items():
        encoding = output_encoding_of(ship)
        shipped = dataclasses.replace(scene, encoding=encoding) if encoding else scene
        stacks = {
            view: transform_stack(ship, renders[view], view=view,
                                  seed=derive_seed("calibration-output", seed, label, view))
            for view in ("left", "right")
        }
        for row in statistic_rows(stacks, shipped, settings, f"{scene.label}|output|{label}"):
            rows.append({**design, "transform": label, "region": row["region"],
                         "method": row["method"], "rho": row["rho"],
                         "boot_low": row["boot_low"], "boot_high": row["boot_high"],
                         "chance_se": row["chance_se"], "n_pixels": row["n_pixels"]})
        if encoding:
            shares = []
            for view, stack in stacks.items():
                mean, variance = variance_field(np.asarray(stack))
                q = quantisation_variance(mean, encoding)
                valid = np.asarray(scene.ground_truth[view]["valid"], dtype=bool)
                shares.append(fixed_share(variance[valid], q[valid]))
            rows.append({**design, "transform": label, "region": "all",
                         "method": QUANTISED_SHARE, "rho": max(shares),
                         "boot_low": float("nan"), "boot_high": float("nan"),
                         "chance_se": float("nan"), "n_pixels": int(valid.sum())})
    return rows
