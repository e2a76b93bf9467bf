"""The moment-store contract: ``results/{renderer}/renders/{scene}/{view}/spp{spp}/moments.zarr``.

One store per scene, view and SPP holds the raw per-pixel sample moments of the two
independent half renders of the ``moments`` estimator (:mod:`stereovar.estimators.moments`):

``sample_mean`` (half, y, x, channel)
    float32 :math:`\\frac1{n_h} \\sum_k f_{k,c}` over half :math:`h`'s finite samples
    [W m-2 sr-1];
``sample_mean_sq`` (half, y, x, channel)
    float32 :math:`\\frac1{n_h} \\sum_k f_{k,c}^2` [W2 m-4 sr-2];
``n_samples`` (half, y, x)
    int32 :math:`n_h`, the half's samples with every channel finite;
coordinates
    ``half`` (0, 1), ``sampler_seed`` and ``half_spp`` (half; the seed passed to the
    renderer and the samples per pixel it took), ``y``, ``x`` [px], ``channel`` and the
    scalar ``view``;
attrs
    the render provenance of :mod:`stereovar.io.renders` (``spp`` is the two halves'
    total).

The sums :math:`\\sum f` and :math:`\\sum f^2` are ``n_samples`` times the stored means, so
the variance field at any SPP follows without rendering again
(:func:`stereovar.estimators.moments.pixel_variance`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from .renders import CHANNELS, IMAGE_DIMS, RADIANCE_UNITS, pixel_coords

MOMENT_VARIABLES = ("sample_mean", "sample_mean_sq", "n_samples")
"""Variables of a moment store."""


def moments_dataset(
    halves: Sequence, *, view: str, sampler_seeds, half_spp, attrs: dict
) -> xr.Dataset:
    """The moment-store dataset of the half renders of one view.

    Parameters
    ----------
    halves : sequence of SampleMoments
        :class:`~stereovar.renderers.base.SampleMoments` of each half render, in order.
    view : {"left", "right"}
    sampler_seeds, half_spp : sequence of int
        The sampler seed and the samples per pixel of each half.
    attrs : dict
        Provenance (dataset attrs).

    Returns
    -------
    xarray.Dataset
    """
    halves = list(halves)
    if not len(halves) == len(sampler_seeds) == len(half_spp) or not halves:
        raise ValueError(
            f"{len(halves)} half renders for {len(sampler_seeds)} sampler seeds and "
            f"{len(half_spp)} SPP values"
        )
    mean = np.stack([np.asarray(h.mean, np.float32) for h in halves])
    mean_sq = np.stack([np.asarray(h.mean_sq, np.float32) for h in halves])
    count = np.stack([np.asarray(h.count, np.int32) for h in halves])
    if mean.ndim != 4 or mean.shape[-1] != len(CHANNELS) or mean_sq.shape != mean.shape:
        raise ValueError(f"sample moments must have shape (H, W, 3), got {mean.shape[1:]}")
    if count.shape != mean.shape[:-1]:
        raise ValueError(f"sample counts have shape {count.shape[1:]}, not {mean.shape[1:3]}")
    n_half = np.asarray(half_spp, dtype=np.int64)
    if (count > n_half[:, None, None]).any() or (count < 0).any():
        raise ValueError("a pixel counts more finite samples than its half rendered")
    dims = ("half", *IMAGE_DIMS)
    return xr.Dataset(
        {
            "sample_mean": (
                dims,
                mean,
                {"units": RADIANCE_UNITS, "long_name": "mean of the finite samples"},
            ),
            "sample_mean_sq": (
                dims,
                mean_sq,
                {
                    "units": "W2 m-4 sr-2",
                    "long_name": "mean of the squared finite samples",
                },
            ),
            "n_samples": (
                ("half", "y", "x"),
                count,
                {"long_name": "samples with every channel finite"},
            ),
        },
        coords={
            "half": ("half", np.arange(len(halves)), {"long_name": "independent half render"}),
            "sampler_seed": (
                "half",
                np.asarray(sampler_seeds, dtype=np.int64),
                {"long_name": "sampler seed passed to the renderer"},
            ),
            "half_spp": ("half", n_half, {"long_name": "samples per pixel rendered"}),
            **pixel_coords(mean.shape[1], mean.shape[2]),
            "channel": ("channel", list(CHANNELS), {"long_name": "colour channel"}),
            "view": ((), view, {"long_name": "stereo view"}),
        },
        attrs=dict(attrs),
    )


def load_moments(path) -> xr.Dataset:
    """Read a moment store into memory, checked (one-line :class:`StoreError` with the
    rebuild command when it is missing, incomplete or not a moment store)."""
    from .store import load_store, store_error

    ds = load_store(path, "moment store")
    missing = [v for v in MOMENT_VARIABLES if v not in ds]
    if missing:
        raise store_error(path, f"no {', '.join(missing)}", what="moment store")
    if ds["sample_mean"].dims != ("half", *IMAGE_DIMS):
        raise store_error(
            path, f"sample_mean has dims {ds['sample_mean'].dims}", what="moment store"
        )
    return ds
