"""Image file formats by extension: OpenEXR, PFM, PNG, NPY, NPZ, HDF5 and TIFF.

:mod:`stereovar.io.images` reads them and :mod:`stereovar.io.writers` writes them (all but HDF5
and TIFF); ``.h5`` is HDF5 and ``.tif`` TIFF, and a TIFF is read as a field only.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import ImageError

FORMATS = ("exr", "pfm", "png", "npy", "npz", "hdf5", "tiff")
"""File formats (``.exr``, ``.pfm``, ``.png``, ``.npy``, ``.npz``, ``.hdf5``, ``.tiff``)."""

ALIASES = {"h5": "hdf5", "tif": "tiff"}
"""Other extensions of a format."""

FIELD_ONLY = ("tiff",)
"""Formats read as fields (depth, disparity, a mask) only, never as a render."""


def image_format(path) -> str:
    """The format of ``path`` from its extension (one of :data:`FORMATS`; ``.h5`` is
    ``hdf5``, ``.tif`` is ``tiff``).

    Examples
    --------
    >>> image_format("a/0.hdf5"), image_format("b.h5"), image_format("depth_00000.tif")
    ('hdf5', 'hdf5', 'tiff')
    """
    ext = Path(path).suffix.lower().lstrip(".")
    ext = ALIASES.get(ext, ext)
    if ext not in FORMATS:
        raise ImageError(
            f"{path}: unknown image format '.{ext}'; use one of "
            f"{', '.join('.' + f for f in FORMATS)}"
        )
    return ext
