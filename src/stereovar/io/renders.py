"""The render-store contract: build, check and read ``results/{renderer}/renders/...`` stores.

A render store holds the renders of one scene, view and SPP for a batch of seed indices:

``radiance`` (seed, y, x, channel)
    float32 linear RGB radiance [W m-2 sr-1], chunked one seed at a time.
coordinates
    ``seed`` (seed index), ``sampler_seed`` (seed; the value passed to the renderer),
    ``n_nonfinite_pixels`` (seed; pixels with a NaN or Inf), ``y``, ``x`` [px], ``channel``
    (R, G, B) and the scalar ``view``.
attrs
    Provenance: ``scene``, ``scene_digest``, ``renderer``, ``renderer_version``, ``variant``,
    ``spp``, ``seed_policy``, the render settings and ``config_digest``.

``xr.open_mfdataset(paths, combine="nested", concat_dim="seed")`` stacks the stores of one view.
Anything that writes this contract (the render jobs, an importer of external renders) feeds
the estimators unchanged. Readers check completeness first and stream one seed (or one row
block) at a time.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import StoreError
from .store import ZARR_FORMAT, read_errors, rebuild_command, store_error

IMAGE_DIMS = ("y", "x", "channel")
"""Dims of one render."""

RADIANCE_UNITS = "W m-2 sr-1"
"""Units of stored radiance (Mitsuba's and Cycles' linear radiance scale)."""

CHANNELS = ("R", "G", "B")


def pixel_coords(height: int, width: int) -> dict:
    """``y`` and ``x`` pixel-index coordinates with units, for every stored image."""
    return {
        "y": ("y", np.arange(int(height)), {"units": "px", "long_name": "pixel row"}),
        "x": ("x", np.arange(int(width)), {"units": "px", "long_name": "pixel column"}),
    }


def render_dataset(
    images, *, view: str, seeds, sampler_seeds, attrs: dict, n_nonfinite=None
) -> xr.Dataset:
    """The render-store dataset of a batch of renders of one view.

    Parameters
    ----------
    images : array_like, shape (n, H, W, 3)
        The renders, in ``seeds`` order.
    view : {"left", "right"}
    seeds, sampler_seeds : sequence of int
        Seed indices and the sampler seeds passed to the renderer.
    attrs : dict
        Provenance (dataset attrs).
    n_nonfinite : array_like of int, optional
        Pixels with a NaN or Inf in any channel, per render, when the caller has counted
        them already (they are counted here otherwise).

    Returns
    -------
    xarray.Dataset
    """
    stack = np.asarray(images, dtype=np.float32)
    if stack.ndim != 4 or stack.shape[-1] != len(CHANNELS):
        raise ValueError(f"images must have shape (n, H, W, 3), got {stack.shape}")
    if not len(seeds) == len(sampler_seeds) == stack.shape[0]:
        raise ValueError(
            f"{stack.shape[0]} images for {len(seeds)} seeds and {len(sampler_seeds)} sampler seeds"
        )
    if n_nonfinite is None:
        n_bad = (~np.isfinite(stack)).any(axis=-1).sum(axis=(1, 2)).astype(np.int64)
    else:
        n_bad = np.asarray(n_nonfinite, dtype=np.int64)
    return xr.Dataset(
        {
            "radiance": (
                ("seed", *IMAGE_DIMS),
                stack,
                {"units": RADIANCE_UNITS, "long_name": "linear RGB radiance of one render"},
            )
        },
        coords={
            "seed": ("seed", np.asarray(seeds, dtype=np.int64), {"long_name": "seed index"}),
            "sampler_seed": (
                "seed",
                np.asarray(sampler_seeds, dtype=np.int64),
                {"long_name": "sampler seed passed to the renderer"},
            ),
            "n_nonfinite_pixels": (
                "seed",
                n_bad,
                {"long_name": "pixels with a NaN or Inf in any channel"},
            ),
            **pixel_coords(stack.shape[1], stack.shape[2]),
            "channel": ("channel", list(CHANNELS), {"long_name": "colour channel"}),
            "view": ((), view, {"long_name": "stereo view"}),
        },
        attrs=dict(attrs),
    )


class RenderStore:
    """One render store's ``radiance`` array opened with zarr, checked for completeness.

    Stores with a ``seed`` dim hold several renders; a store on ``(y, x, channel)`` alone holds
    one. Nothing is read until :meth:`rows`.

    Attributes
    ----------
    path : path-like
    shape : tuple of int
        ``(H, W, C)`` of one render.
    n_seeds : int
        Renders in the store.
    coords : dict
        ``y``, ``x`` and ``channel`` coordinate values when stored.
    attrs : dict
        The dataset's provenance attrs.
    """

    def __init__(self, path):
        import zarr

        self.path = path
        if not Path(path).exists():
            raise StoreError(
                f"render store {path} does not exist; build it with `{rebuild_command(path)}`"
            )
        try:
            group = zarr.open_consolidated(str(path), mode="r", zarr_format=ZARR_FORMAT)
            if "radiance" not in group:
                raise store_error(path, "no 'radiance' array")
            array = group["radiance"]
            dims = tuple(array.attrs.get("_ARRAY_DIMENSIONS", ()))
            image_dims = tuple(d for d in dims if d != "seed")
            if set(image_dims) != set(IMAGE_DIMS) or len(dims) != array.ndim:
                raise store_error(path, f"dims {dims} instead of (seed, y, x, channel)")
            # a missing chunk file reads back as the fill value, so count the stored chunks
            stored, total = array.nchunks_initialized, array.nchunks
            self.coords = {k: group[k][:] for k in IMAGE_DIMS if k in group}
            # provenance on the dataset; a store written from a bare DataArray has it on the
            # variable instead
            own = {k: v for k, v in array.attrs.items() if not k.startswith("_")}
            self.attrs = {**own, **dict(group.attrs)}
        except read_errors() as exc:
            raise store_error(path, f"{type(exc).__name__}: {exc}") from exc
        if stored < total:
            raise store_error(path, f"{total - stored} of {total} chunks missing")
        self.array = array
        self._seed_axis = dims.index("seed") if "seed" in dims else None
        self.order = tuple(dims.index(k) for k in IMAGE_DIMS)
        self.shape = tuple(array.shape[i] for i in self.order)
        self.n_seeds = 1 if self._seed_axis is None else int(array.shape[self._seed_axis])

    def rows(self, rows: slice, seed: int = 0) -> np.ndarray:
        """Rows ``rows`` of the ``seed``-th render in the store, as (y, x, channel)."""
        index = [slice(None)] * self.array.ndim
        index[self.order[0]] = rows
        order = self.order
        if self._seed_axis is not None:
            index[self._seed_axis] = int(seed)
            order = tuple(a - (a > self._seed_axis) for a in self.order)
        try:
            return np.transpose(self.array[tuple(index)], order)
        except read_errors() as exc:
            raise store_error(self.path, f"{type(exc).__name__}: {exc}") from exc


def iter_renders(paths):
    """Yield ``(store, seed position)`` for every render of ``paths``, store by store."""
    for path in paths:
        store = RenderStore(path)
        for k in range(store.n_seeds):
            yield store, k


class LazyRenders:
    """The renders of one view as a sequence that reads one render per item (never all).

    Parameters
    ----------
    paths : sequence of path-like
        Render stores of one view.
    """

    def __init__(self, paths):
        self._index = list(iter_renders(paths))  # each store opened (and checked) once

    def __len__(self):
        return len(self._index)

    def __getitem__(self, k):
        store, seed = self._index[k]
        return store.rows(slice(None), seed)

    def __iter__(self):
        for k in range(len(self)):
            yield self[k]
