"""The pixels of each image format as its library decodes them.

For the readers of :mod:`stereovar.io.images`: an EXR's channels across all its parts, a PNG's
samples or palette indices, a TIFF's values, an NPY's or NPZ's array, and integer values
decoded to linear floats.
"""

from __future__ import annotations

import numpy as np

from ..errors import ImageError
from .channels import field_channel, render_channels, unique_channels
from .headers import _npz_key
from .transfer import srgb_to_linear


def _exr_channels(path) -> dict:
    """Every channel of an EXR across all its parts: name to its ``(H, W)`` pixels.

    A multi-part file whose parts repeat a channel name (a multi-view file: one part per pass
    and view) is refused (:func:`~stereovar.io.channels.unique_channels`).
    """
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        parts = [
            (part.header.get("view"), {name: ch.pixels for name, ch in part.channels.items()})
            for part in f.parts
            if len(part.channels) == len(part.header["channels"])
        ]
        if len(parts) != len(f.parts) or not parts:  # the bindings drop an unreadable part
            raise ValueError("its pixel data cannot be decoded")
    unique_channels(((view, list(channels)) for view, channels in parts), path)
    return {name: pixels for _, channels in parts for name, pixels in channels.items()}


def _exr_rgb(path, channel: str | None = None) -> np.ndarray:
    """The render of an EXR: ``(H, W, 3)`` from the R, G and B of its render layer (plain,
    Blender's ``ViewLayer.Combined``, Kubric's ``rgba``, BlenderProc's ``colors``), or
    ``(H, W)`` from its one grey channel; ``channel`` names the layer
    (:func:`~stereovar.io.channels.render_channels`)."""
    channels = _exr_channels(path)
    picked = render_channels(channels, path, channel)
    if len(picked) == 1:
        return channels[picked[0]]
    return np.stack([channels[c] for c in picked], axis=-1)


def _exr_field(channels: dict, path, role: str | None = None, channel: str | None = None):
    """The one channel of ``channels`` holding ``role``
    (:func:`~stereovar.io.channels.field_channel`)."""
    return channels[field_channel(channels, role, path, channel)]


def _palette_indices(path) -> np.ndarray:
    """The palette indices of a palette PNG (Kubric's ``segmentation_%05d.png``,
    ``write_palette_png``: the index is the segment id), through Pillow: OpenCV returns
    the palette's colours instead."""
    from PIL import Image

    with Image.open(path) as image:
        if image.mode != "P":
            raise ValueError(f"a palette PNG read in mode {image.mode}")
        return np.asarray(image)


def _png(path) -> tuple[np.ndarray, int]:
    """Pixels (RGB order, or grey) and bit depth of a PNG."""
    import cv2

    a = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if a is None:
        raise ValueError("OpenCV could not decode it")
    if a.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"unsupported sample type {a.dtype}")
    if a.ndim == 3:
        a = a[..., 2::-1] if a.shape[-1] >= 3 else a[..., :1]
    return a, 8 * a.dtype.itemsize


def _array(path, fmt) -> np.ndarray:
    if fmt == "npy":
        return np.load(path, allow_pickle=False)
    with np.load(path, allow_pickle=False) as z:
        return z[_npz_key(z, path)]


def _decode_png(a: np.ndarray, depth: int, transfer: str, scale: float) -> np.ndarray:
    v = a.astype(np.float64) / (2**depth - 1)
    if transfer == "srgb":
        v = srgb_to_linear(v)
    return (v * scale).astype(np.float32)


def _decode_integer(a: np.ndarray, path, transfer: str, scale: float) -> np.ndarray:
    """An integer render (HDF5 ``uint8`` or ``uint16`` colors) decoded as a PNG's values are
    (:func:`_decode_png`); floats are returned as they are (linear)."""
    if a.dtype.kind == "f":
        return a
    if a.dtype not in (np.uint8, np.uint16):
        raise ImageError(
            f"{path}: a render of type {a.dtype}; BlenderProc writes colors as uint8, "
            "uint16 or float"
        )
    return _decode_png(a, 8 * a.dtype.itemsize, transfer, scale)


def _tiff(path) -> np.ndarray:
    """A TIFF's values as stored, through OpenCV: ``(H, W)``, or its colour channels in
    R, G, B order (OpenCV reads them as B, G, R; an alpha channel is left out)."""
    import cv2

    a = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if a is None:
        raise ValueError("OpenCV could not decode it")
    if a.ndim == 3 and a.shape[-1] >= 3:
        a = a[..., 2::-1]
    return a
