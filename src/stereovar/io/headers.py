"""What an image file's header says, no pixel decoded.

Its size (:func:`image_size`), whether its render is stored as half floats
(:func:`stored_as_half`) or as integers of how many bits (:func:`integer_bits`), and the header
fields of each format that say it (PNG's IHDR chunk, a TIFF's first directory, an NPY's
header).
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from ..errors import ImageError
from . import hdf5
from .channels import render_channels
from .exr_header import channel_types
from .files import _quiet, open_regular, reading_header, regular_file
from .formats import image_format
from .pfm import _pfm_header


def image_size(path) -> tuple[int, int]:
    """``(height, width)`` of an image file from its header alone (no pixel is decoded).

    Raises
    ------
    ImageError
        The file is missing, not a regular file, or its header is unreadable.
    """
    fmt = image_format(path)
    path = Path(path)
    with open_regular(path) as f, reading_header(path), _quiet():
        return _header_size(f, fmt, path)


def _header_size(f, fmt, path) -> tuple[int, int]:
    if fmt == "exr":
        import OpenEXR

        with OpenEXR.File(f, header_only=True) as exr:
            sizes = {_window_size(part.header["dataWindow"]): part.name() for part in exr.parts}
        if len(sizes) > 1:
            parts = ", ".join(f"{name or 'unnamed'} {w}x{h}" for (h, w), name in sizes.items())
            raise ImageError(
                f"{path}: its parts differ in size ({parts}); export every pass at one resolution"
            )
        return next(iter(sizes))
    if fmt == "pfm":
        _, width, height, _, _ = _pfm_header(f)
        return height, width
    if fmt == "png":
        head = f.read(26)
        if head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
            raise ValueError("no PNG signature")
        width, height = struct.unpack(">II", head[16:24])
        return int(height), int(width)
    if fmt == "npy":
        return tuple(_npy_header(f)[0][:2])
    if fmt == "hdf5":
        return hdf5.size(path)
    if fmt == "tiff":
        return tiff_size(f)
    with np.load(f) as z:
        return tuple(z[_npz_key(z, path)].shape[:2])


TIFF_WIDTH, TIFF_LENGTH = 256, 257
"""The TIFF tags of an image's width and height (TIFF 6.0, Section 8)."""


def tiff_size(f) -> tuple[int, int]:
    """``(height, width)`` of a TIFF's first image from its header: the byte order
    (``II`` or ``MM``), the magic 42 and the first image file directory's ``ImageWidth``
    and ``ImageLength`` entries (TIFF 6.0, Sections 2 and 8); BigTIFF (magic 43) too.

    Parameters
    ----------
    f : binary file object
        Opened at its start.

    Examples
    --------
    >>> import io
    >>> entries = struct.pack("<HHHII", 2, 256, 3, 1, 640) + struct.pack("<HHII", 257, 4, 1, 480)
    >>> head = b"II" + struct.pack("<HI", 42, 8) + entries
    >>> tiff_size(io.BytesIO(head))
    (480, 640)
    """
    order = f.read(2)
    if order not in (b"II", b"MM"):
        raise ValueError("no TIFF byte-order mark")
    e = "<" if order == b"II" else ">"
    (magic,) = struct.unpack(e + "H", f.read(2))
    big = magic == 43
    if magic not in (42, 43):
        raise ValueError(f"TIFF magic {magic} is neither 42 nor 43")
    if big:
        f.read(4)  # offset size and padding
        (offset,) = struct.unpack(e + "Q", f.read(8))
        count_fmt, entry_size = "Q", 20
    else:
        (offset,) = struct.unpack(e + "I", f.read(4))
        count_fmt, entry_size = "H", 12
    f.seek(offset)
    (count,) = struct.unpack(e + count_fmt, f.read(struct.calcsize(count_fmt)))
    found = {}
    for _ in range(count):
        entry = f.read(entry_size)
        tag, kind = struct.unpack(e + "HH", entry[:4])
        value = entry[12:] if big else entry[8:]
        if tag in (TIFF_WIDTH, TIFF_LENGTH):
            code = "H" if kind == 3 else ("Q" if kind == 16 else "I")
            found[tag] = struct.unpack(e + code, value[: struct.calcsize(code)])[0]
    if len(found) < 2:
        raise ValueError("no ImageWidth or ImageLength entry")
    return int(found[TIFF_LENGTH]), int(found[TIFF_WIDTH])


def _npy_header(f) -> tuple:
    """``(shape, fortran_order, dtype)`` from the header of an NPY file or stream."""
    npy = np.lib.format
    version = npy.read_magic(f)  # versions 2 and 3 share a header layout
    read = npy.read_array_header_1_0 if version == (1, 0) else npy.read_array_header_2_0
    return read(f)


def stored_as_half(path, *, channel: str | None = None) -> bool | None:
    """Whether the render :func:`~stereovar.io.images.read_image` reads from ``path`` is
    stored as half floats, as the file's header says (no pixel is decoded).

    Parameters
    ----------
    path : path-like
    channel : str, optional, keyword-only
        EXR only: ``audit.channels.render``, as for :func:`~stereovar.io.images.read_image`.

    Returns
    -------
    bool or None
        EXR: whether a channel of the render (its ``R, G, B`` or its one grey channel,
        picked as :func:`~stereovar.io.images.read_image` picks them) has pixel type ``HALF``
        (:func:`stereovar.io.exr_header.channel_types`); NPY, NPZ and HDF5: whether the
        render's dtype is float16. None for PFM and PNG, whose headers cannot say it (PFM
        holds float32 only, PNG integers).

    Raises
    ------
    ImageError
        The file cannot be opened, is not a regular file, or its header is unreadable.
    """
    fmt = image_format(path)
    if fmt not in ("exr", "npy", "npz", "hdf5"):
        return None
    with open_regular(path) as f, reading_header(path):
        if fmt == "hdf5":
            return hdf5.render_dtype(path, channel) == np.float16
        if fmt == "exr":
            types = channel_types(f)
            return any(types[c] == "half" for c in render_channels(types, path, channel))
        if fmt == "npy":
            return _npy_header(f)[2] == np.float16
        with np.load(f) as z:
            key = _npz_key(z, path)
            member = key if key in z.zip.namelist() else f"{key}.npy"
            with z.zip.open(member) as array:
                return _npy_header(array)[2] == np.float16


def _window_size(window) -> tuple[int, int]:
    """``(height, width)`` of an EXR data window ``(min, max)``, both inclusive."""
    lo, hi = window
    return int(hi[1] - lo[1] + 1), int(hi[0] - lo[0] + 1)


PNG_PALETTE = 3
"""The PNG colour type of a palette image (PNG specification, Section 11.2.2, IHDR)."""


def png_header(path) -> tuple[int, int]:
    """``(bit depth, colour type)`` of a PNG from its IHDR chunk (PNG specification,
    Section 11.2.2): 8 or 16 bits, colour type 0 grey, 2 RGB, 3 palette, 4 grey and alpha,
    6 RGBA."""
    with open(path, "rb") as f:
        head = f.read(26)
    if head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR" or len(head) < 26:
        raise ValueError("no PNG signature")
    return head[24], head[25]


def _npz_key(z, path) -> str:
    keys = list(z.keys())
    if len(keys) != 1:
        raise ImageError(
            f"{path}: {len(keys)} arrays ({', '.join(keys) or 'none'}); store one array per "
            ".npz file"
        )
    return keys[0]


def integer_bits(path, *, channel: str | None = None) -> int | None:
    """The bits per sample of a render stored as integers, from the file's header: a PNG's
    bit depth, the dtype of a BlenderProc HDF5 file's integer ``colors``; None for a
    render stored as floats (EXR, PFM, a float NPY or HDF5 dataset) or in NPY/NPZ.

    Integer renders are display-referred: :func:`~stereovar.io.images.read_image` decodes
    them with ``transfer`` and ``scale``, and the import warns about their quantisation and
    clipping.
    """
    fmt = image_format(path)
    if fmt not in ("png", "hdf5"):
        return None
    regular_file(path)
    with reading_header(path):
        if fmt == "png":
            return png_header(path)[0]
        dtype = hdf5.render_dtype(path, channel)
        return 8 * dtype.itemsize if dtype.kind == "u" else None
