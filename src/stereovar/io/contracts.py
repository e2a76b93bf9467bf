"""The stored contracts downstream of the renders: variance and warped stores, provenance.

``results/{renderer}/{estimator}/variance/{scene}/spp{spp}.zarr`` (:func:`variance_store`)
    ``mean`` (view, y, x, channel) [W m-2 sr-1], ``variance`` (view, y, x)
    [W2 m-4 sr-2], ``finite`` and ``n_nonfinite`` (view, y, x).
``results/{renderer}/{estimator}/warped/{scene}/spp{spp}.zarr`` (:func:`warped_store`)
    ``warped_variance`` (y, x), ``omega``, ``omega_geometry``, ``usable`` and
    ``region_{all,non_glass,glass}`` (y, x).

Every variable has ``units`` (or is a mask) and ``long_name``; ``y`` and ``x`` are pixel
coordinates; the dataset attrs carry the provenance of the renders they came from plus the
estimator.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np
import xarray as xr

from .renders import RADIANCE_UNITS, pixel_coords

VARIANCE_UNITS = "W2 m-4 sr-2"
"""Units of a variance of radiance."""

RENDER_PROVENANCE = (
    "scene",
    "scene_digest",
    "spp",
    "renderer",
    "renderer_version",
    "variant",
    "jit_target",
    "width",
    "height",
    "integrator",
    "max_depth",
    "rfilter",
    "sampler",
    "seed_policy",
    "config_digest",
    "bit_depth",
    "transfer",
    "full_scale",
    "file_format",
)
"""Render attrs carried into every store computed from the renders. An audit's imported
renders also say how they were stored (``bit_depth``, 0 for floats; the ``transfer`` that
decoded them; ``full_scale``; ``file_format``: :func:`stereovar.audit.importer.import_frame`),
through which the calibration draws their matched null
(:func:`stereovar.jobs.calibration.scene_frames`); the project's own renders carry none."""


def config_digest(settings: dict) -> str:
    """SHA-256 of the settings that determine an artefact (canonical JSON, sorted keys)."""
    text = json.dumps(settings, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def render_provenance(attrs: dict) -> dict:
    """The :data:`RENDER_PROVENANCE` entries of a render store's attrs."""
    return {k: attrs[k] for k in RENDER_PROVENANCE if k in attrs}


def variance_store(ds: xr.Dataset, *, estimator: str, provenance: dict) -> xr.Dataset:
    """Units, names, pixel coordinates and provenance on an estimator's output.

    Parameters
    ----------
    ds : xarray.Dataset
        :meth:`stereovar.estimators.base.VarianceEstimator.estimate` output.
    estimator : str
        The ``render.estimator`` name.
    provenance : dict
        Render provenance (:func:`render_provenance`).

    Returns
    -------
    xarray.Dataset
        ``ds`` with ``units`` on ``mean`` and ``variance``, ``y``/``x`` coordinates, and attrs
        ``estimator`` (name), ``estimator_description``, ``n_seeds`` (renders per view),
        ``n_draws`` (independent draws behind each pixel's variance: the :math:`N` seeds, or
        the samples of the ``moments`` estimator) plus ``provenance``.
    """
    missing = {"mean", "variance", "finite", "n_nonfinite"} - set(ds.data_vars)
    if missing:
        raise ValueError(f"estimator output lacks {sorted(missing)}")
    out = ds.assign_coords(pixel_coords(ds.sizes["y"], ds.sizes["x"]))
    out["mean"].attrs["units"] = RADIANCE_UNITS
    for name in ("variance", "half_variance", "subset_variance"):
        if name in out:
            out[name].attrs["units"] = VARIANCE_UNITS
    out["view"].attrs["long_name"] = "stereo view"
    description = ds.attrs.get("estimator", "")
    out.attrs = {
        **provenance,
        "n_seeds": int(ds.attrs["n_seeds"]),
        "n_draws": int(ds.attrs.get("n_draws", ds.attrs["n_seeds"])),
        "estimator": estimator,
        "estimator_description": description,
    }
    return out


def warped_store(aligned: dict, masks: dict, *, attrs: dict) -> xr.Dataset:
    """The Eq. 2 store: the warped right field, the valid sets and the region masks.

    Parameters
    ----------
    aligned : dict
        :func:`stereovar.statistics.warp.align_variance` output.
    masks : dict
        :func:`stereovar.statistics.regions.region_masks` of ``aligned["omega"]``.
    attrs : dict
        Dataset attrs (the variance store's, plus the ground truth's sign and convention).
    """
    dims = ("y", "x")
    height, width = np.shape(aligned["warped"])
    return xr.Dataset(
        {
            "warped_variance": (
                dims,
                aligned["warped"],
                {
                    "units": VARIANCE_UNITS,
                    "long_name": "right variance field in left coordinates (Eq. 2); 0 outside"
                    " omega_geometry",
                },
            ),
            "omega": (dims, aligned["omega"], {"long_name": "valid set of Eq. 3"}),
            "omega_geometry": (
                dims,
                aligned["omega_geometry"],
                {"long_name": "valid set of the warp from the ground truth alone"},
            ),
            "usable": (
                dims,
                aligned["usable"],
                {"long_name": "left value and warped right value built from finite renders"},
            ),
            **{
                f"region_{k}": (dims, np.asarray(m), {"long_name": f"omega restricted to {k}"})
                for k, m in masks.items()
            },
        },
        coords=pixel_coords(height, width),
        attrs=dict(attrs),
    )


def read_alignment(warped: xr.Dataset) -> dict:
    """The :func:`~stereovar.statistics.warp.align_variance` dict from a warped store."""
    return {
        "warped": warped["warped_variance"].values,
        **{k: warped[k].values for k in ("omega", "omega_geometry", "usable")},
    }
