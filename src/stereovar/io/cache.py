"""Content-addressed cache of single renders: a finished render is never lost.

Snakemake deletes a job's outputs before it runs the job, so a render batch whose rerun fails
(a bad variant, a typo in a spec) would lose every render in it. Each render is therefore also
kept here, under the SHA-256 of everything that determines its pixels
(:func:`render_key`): the scene's content (the spec and every file an XML scene reads), the
renderer with its version, the variant actually used, the CPU target its kernels are compiled
for (:mod:`stereovar.renderers.mitsuba.jit_target`) and the code that compiles scenes, the
rig, the view, the SPP, the sampler seed and the integrator, filter and sampler. The workflow
never deletes this directory; a render job whose key is present reads the render instead of
rendering it, so a failed or interrupted run costs only the renders it had not finished.

An entry is one Zarr store written atomically (:func:`stereovar.io.store.write_dataset`) with
its key in its attributes; an entry that cannot be read back, or whose key differs, is a miss
and is rendered and written again.
"""

from __future__ import annotations

import hashlib
import json
import logging
from collections.abc import Mapping
from pathlib import Path

import numpy as np

log = logging.getLogger("stereovar")

KEY_FIELDS = (
    "scene_digest",
    "renderer",
    "renderer_version",
    "variant",
    "jit_target",
    "renderer_code",
    "width",
    "height",
    "baseline_m",
    "convention",
    "view",
    "spp",
    "sampler_seed",
    "integrator",
    "max_depth",
    "rfilter",
    "sampler",
)
"""What determines a render's pixels, and so its cache key."""

OPTIONAL_KEY_FIELDS = ("renderer_options",)
"""Part of the key when a render has them: the options only one renderer reads
(``render.cycles``: the denoiser, adaptive sampling, the seed rule, ...)."""


def render_key(determining: Mapping) -> str:
    """SHA-256 of the :data:`KEY_FIELDS` (and any :data:`OPTIONAL_KEY_FIELDS`) of one render
    (canonical JSON).

    Raises
    ------
    KeyError
        A key field is missing (a key that left one out could serve a wrong render).
    """
    missing = [k for k in KEY_FIELDS if k not in determining]
    if missing:
        raise KeyError(f"render key needs {', '.join(missing)}")
    fields = {k: determining[k] for k in KEY_FIELDS}
    fields.update({k: determining[k] for k in OPTIONAL_KEY_FIELDS if k in determining})
    text = json.dumps(fields, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def source_digest(package_dirs) -> str:
    """SHA-256 of the ``*.py`` files under ``package_dirs`` (sorted by path): the code that
    turns a scene spec into pixels, part of :func:`render_key`."""
    h = hashlib.sha256()
    for root in package_dirs:
        root = Path(root)
        files = sorted(root.rglob("*.py")) if root.is_dir() else [root]
        for path in files:
            h.update(path.name.encode())
            h.update(path.read_bytes())
    return h.hexdigest()


class RenderCache:
    """Single renders stored by key under ``root`` (``render.cache`` in the config).

    Parameters
    ----------
    root : path-like
        Cache directory; created on the first :meth:`put`.
    """

    def __init__(self, root):
        self.root = Path(root)

    def path(self, key: str) -> Path:
        """Where the entry of ``key`` lives."""
        return self.root / key[:2] / f"{key}.zarr"

    def get(self, key: str) -> np.ndarray | None:
        """The render stored under ``key`` (float32, (H, W, C)), or None when absent or
        unreadable (logged; the caller renders it again)."""
        from .store import open_dataset, read_errors

        path = self.path(key)
        if not path.exists():
            return None
        try:
            ds = open_dataset(path)
            if ds.attrs.get("render_key") != key:
                raise ValueError(f"it holds key {ds.attrs.get('render_key')!r}")
            image = np.asarray(ds["radiance"].values, dtype=np.float32)
            if image.ndim != 3:
                raise ValueError(f"radiance has shape {image.shape}")
        except read_errors() as err:
            log.warning("render cache entry %s is unreadable (%s); rendering it again", path, err)
            return None
        return image

    def put(self, key: str, image, attrs: Mapping, *, channels=None) -> Path:
        """Store one render (H, W, C) under ``key`` atomically, with ``attrs`` and the key.

        ``channels`` names the C channels (default R, G, B; e.g. the seven channels of
        :meth:`stereovar.renderers.base.SampleMoments.stack`)."""
        import xarray as xr

        from .store import write_dataset

        names = list(channels) if channels is not None else ["R", "G", "B"][: np.shape(image)[-1]]
        ds = xr.Dataset(
            {"radiance": (("y", "x", "channel"), np.asarray(image, dtype=np.float32))},
            coords={"channel": names},
            attrs={**{k: v for k, v in attrs.items() if v is not None}, "render_key": key},
        )
        return write_dataset(ds, self.path(key))
