"""Image files other tools write and read: OpenEXR, PFM, PNG (8 and 16 bit), NPY, NPZ, and
the generators' own formats: BlenderProc's HDF5 and Kubric's float TIFF.

The audit (:mod:`stereovar.audit`) reads renders, disparity, depth and masks made elsewhere
through :func:`read_image`, :func:`read_field` and :func:`read_labels`; the export writes
ours through :func:`write_image` and :func:`write_field`. The readers return float32 (images:
``(H, W, 3)`` linear RGB; fields: ``(H, W)``), or int64 segment ids (:func:`read_labels`:
integer files keep their ids exactly, however large), and raise
:class:`~stereovar.errors.ImageError`, one line naming the file and the fix, for anything
they cannot read.

Libraries: OpenEXR through the ASWF ``OpenEXR`` bindings (the reference implementation: half
and float channels, multi-part files, header-only reads, multithreaded decoding; ``imageio``
needs the FreeImage plugin, a separate binary download, for EXR); an EXR's channels are read
across all its parts (Blender 5 writes each pass of a multilayer file as a part) and picked
by what their names mean (:mod:`stereovar.io.channels`: ``ViewLayer.Depth.Z`` is depth,
``ViewLayer.Combined`` the render), or as ``audit.channels`` names them;
PNG through OpenCV (the only maintained reader and writer of 16-bit RGB PNG on PyPI; Pillow
reduces 48-bit RGB to 8 bit), except a palette PNG read as a field (Kubric's
``segmentation_%05d.png``), whose palette indices Pillow reads (OpenCV returns the palette's
colours); PFM, a plain header and raw float32 rows stored bottom to top, by hand; NPY and NPZ
through numpy; BlenderProc's HDF5 (``.hdf5``, ``.h5``) through h5py, its datasets picked by
name (:mod:`stereovar.io.hdf5`); TIFF (``.tiff``, ``.tif``: Kubric's float32
``depth_%05d.tiff``) through OpenCV, as a field only.

A file that holds both views (a BlenderProc stereo render: each dataset with a leading axis
of 2) is read one view at a time: the readers' ``view`` (0 left, 1 right) picks it.

A path is read only when it is a regular file: a named pipe, a device or a directory is
refused by its kind before it is opened for reading (:func:`regular_file`), so nothing waits
on a pipe that no one writes to. What the libraries print themselves about a damaged file
(OpenEXR's and libpng's diagnostics) is silenced; the :class:`ImageError` says it once.
"""

from __future__ import annotations

import os
import stat
import struct
from contextlib import ExitStack, contextmanager
from pathlib import Path

import numpy as np

from ..errors import ImageError
from ..renderers.quiet import silenced
from . import hdf5
from .channels import WORDS, field_channel, render_channels, unique_channels
from .exr_header import channel_types

FORMATS = ("exr", "pfm", "png", "npy", "npz", "hdf5", "tiff")
"""File formats (``.exr``, ``.pfm``, ``.png``, ``.npy``, ``.npz``, ``.hdf5``, ``.tiff``)."""

ALIASES = {"h5": "hdf5", "tif": "tiff"}
"""Other extensions of a format."""

FIELD_ONLY = ("tiff",)
"""Formats read as fields (depth, disparity, a mask) only, never as a render."""

TRANSFERS = ("linear", "srgb")
"""Transfer functions of integer images: stored values are linear, or sRGB-encoded."""

_KINDS = {
    stat.S_IFIFO: "a named pipe",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFDIR: "a directory",
    stat.S_IFSOCK: "a socket",
}


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


def srgb_to_linear(v):
    r"""The sRGB decoding function (IEC 61966-2-1) on values in [0, 1].

    .. math::

        L = \begin{cases} V / 12.92 & V \le 0.04045 \\
            \left(\frac{V + 0.055}{1.055}\right)^{2.4} & \text{otherwise} \end{cases}
    """
    v = np.asarray(v, dtype=np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(v):
    r"""The sRGB encoding function (IEC 61966-2-1), the inverse of :func:`srgb_to_linear`.

    .. math::

        V = \begin{cases} 12.92\,L & L \le 0.0031308 \\
            1.055\,L^{1/2.4} - 0.055 & \text{otherwise} \end{cases}
    """
    v = np.clip(np.asarray(v, dtype=np.float64), 0.0, None)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)


# --------------------------------------------------------------------------------------------
# headers
# --------------------------------------------------------------------------------------------


def _unreadable(path, err, what="file") -> ImageError:
    detail = " ".join(str(err).split())[:160]
    return ImageError(
        f"{path}: cannot read the {what} ({detail}); it is truncated or not a valid "
        f"{image_format(path).upper()} file: write it again"
    )


def file_kind(mode: int) -> str:
    """What a file that is not a regular one is, in words, from its ``st_mode``.

    Parameters
    ----------
    mode : int
        The file's ``st_mode`` (:func:`os.stat`, :func:`os.fstat`).

    Returns
    -------
    str
        ``"a named pipe"``, ``"a character device"``, ``"a block device"``, ``"a
        directory"``, ``"a socket"``, or ``"not a file"``.

    Examples
    --------
    >>> file_kind(stat.S_IFIFO | 0o644), file_kind(stat.S_IFDIR | 0o755)
    ('a named pipe', 'a directory')
    """
    return _KINDS.get(stat.S_IFMT(mode), "not a file")


def not_regular_error(path, mode) -> ImageError:
    """The one-line error for ``path`` whose ``st_mode`` is ``mode``: not a regular file."""
    return ImageError(
        f"{path}: not a regular file ({file_kind(mode)}); give the path of an image file"
    )


def unopenable_error(path, err: OSError) -> ImageError:
    """The one-line error for a ``path`` that cannot be opened (``err``): missing
    (:func:`missing_error`) or not readable."""
    if isinstance(err, FileNotFoundError):
        return missing_error(path)
    return ImageError(f"{path}: cannot open it ({err.strerror}); make it readable")


def missing_error(path) -> ImageError:
    """The one-line error for a ``path`` that does not exist."""
    return ImageError(f"{path}: no such file; check the audit path template")


def regular_file(path) -> None:
    """Check that ``path`` is a regular file (a link to one counts) without opening it.

    Raises
    ------
    ImageError
        It does not exist (or is a dangling link), or it is a named pipe, a device, a
        directory or a socket (one line naming the kind).
    """
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise missing_error(path) from None
    except OSError as err:
        raise ImageError(f"{path}: cannot look at it ({err.strerror}); fix its path") from None
    if not stat.S_ISREG(mode):
        raise not_regular_error(path, mode)


@contextmanager
def open_regular(path, *, unopenable=unopenable_error, not_regular=not_regular_error):
    """``path`` opened for binary reading once it is known to be a regular file: the open
    does not block (a named pipe opened for reading would wait for a writer) and the kind
    is checked on the open descriptor, so what is read is the file that was checked.

    Parameters
    ----------
    path : path-like
    unopenable : callable (path, OSError) -> Exception, keyword-only
        The error raised when ``path`` cannot be opened (default: an image file's,
        :func:`unopenable_error`).
    not_regular : callable (path, int) -> Exception, keyword-only
        The error raised for a path whose ``st_mode`` is not a regular file's (default: an
        image file's, :func:`not_regular_error`; :func:`file_kind` names the kind).

    Yields
    ------
    io.BufferedReader
        The open file, closed on leaving the block.
    """
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as err:
        raise unopenable(path, err) from None
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        raise not_regular(path, mode)
    os.set_blocking(fd, True)
    with os.fdopen(fd, "rb") as f:
        yield f


@contextmanager
def _quiet():
    """Silence stdout and stderr while a library reads a file: OpenEXR and libpng print
    their own diagnostics of a damaged file there (OpenEXR's bindings also through Python's
    ``sys.stdout``)."""
    with ExitStack() as stack:
        for fd in (1, 2):
            stack.enter_context(silenced(fd, python=True))
        yield


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


@contextmanager
def reading_header(path):
    """Any library's failure to read the header of ``path`` inside the block as one
    :class:`ImageError` line: the file is truncated or not of its extension's format (an
    HDF5 file cut short cannot be opened at all, so its datasets cannot be listed).

    Parameters
    ----------
    path : path-like
        The file whose header the block reads, named in the line.

    Raises
    ------
    ImageError
        ``path: cannot read the header (<the library's words>); it is truncated or not a
        valid <FORMAT> file: write it again``; an :class:`ImageError` raised inside passes
        as it is.

    Examples
    --------
    >>> with reading_header("a/0.hdf5"):  # doctest: +ELLIPSIS
    ...     raise OSError("Unable to synchronously open file (file signature not found)")
    Traceback (most recent call last):
    ...
    stereovar.errors.ImageError: a/0.hdf5: cannot read the header (Unable to ... not found)); ...
    """
    try:
        yield
    except ImageError:
        raise
    except Exception as err:  # each library raises its own exception types
        raise _unreadable(path, err, "header") from None


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
    """Whether the render :func:`read_image` reads from ``path`` is stored as half floats,
    as the file's header says (no pixel is decoded).

    Parameters
    ----------
    path : path-like
    channel : str, optional, keyword-only
        EXR only: ``audit.channels.render``, as for :func:`read_image`.

    Returns
    -------
    bool or None
        EXR: whether a channel of the render (its ``R, G, B`` or its one grey channel,
        picked as :func:`read_image` picks them) has pixel type ``HALF``
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


# --------------------------------------------------------------------------------------------
# PFM
# --------------------------------------------------------------------------------------------


def _window_size(window) -> tuple[int, int]:
    """``(height, width)`` of an EXR data window ``(min, max)``, both inclusive."""
    lo, hi = window
    return int(hi[1] - lo[1] + 1), int(hi[0] - lo[0] + 1)


def _pfm_header(f):
    tokens = []
    while len(tokens) < 4:
        line = f.readline()
        if not line:
            raise ValueError("header ends early")
        tokens += line.split()
    kind, width, height, scale = tokens[0], int(tokens[1]), int(tokens[2]), float(tokens[3])
    if kind not in (b"PF", b"Pf"):
        raise ValueError(f"magic {kind!r} is neither PF nor Pf")
    return kind == b"PF", width, height, scale, f.tell()


def read_pfm(path) -> np.ndarray:
    """A PFM file as float32, top row first: ``(H, W)`` (``Pf``) or ``(H, W, 3)`` (``PF``).

    PFM stores rows bottom to top; a negative scale means little-endian floats.
    """
    with open(path, "rb") as f:
        color, width, height, scale, _ = _pfm_header(f)
        data = f.read()
    dtype = np.dtype("<f4" if scale < 0 else ">f4")
    shape = (height, width, 3) if color else (height, width)
    count = int(np.prod(shape))
    if len(data) < count * 4:
        raise ValueError(f"{len(data)} bytes of pixel data, {count * 4} expected")
    a = np.frombuffer(data, dtype=dtype, count=count).reshape(shape)
    return np.ascontiguousarray(a[::-1]).astype(np.float32)


def write_pfm(path, array) -> None:
    """Write ``(H, W)`` or ``(H, W, 3)`` values as little-endian PFM (rows bottom to top)."""
    a = np.asarray(array, dtype="<f4")
    if a.ndim == 3 and a.shape[-1] == 3:
        kind = b"PF"
    elif a.ndim == 2:
        kind = b"Pf"
    else:
        raise ValueError(f"PFM holds (H, W) or (H, W, 3) arrays, got {a.shape}")
    with open(path, "wb") as f:
        f.write(kind + b"\n%d %d\n-1.0\n" % (a.shape[1], a.shape[0]))
        f.write(np.ascontiguousarray(a[::-1]).tobytes())


# --------------------------------------------------------------------------------------------
# EXR, PNG, NPY
# --------------------------------------------------------------------------------------------


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


def _npz_key(z, path) -> str:
    keys = list(z.keys())
    if len(keys) != 1:
        raise ImageError(
            f"{path}: {len(keys)} arrays ({', '.join(keys) or 'none'}); store one array per "
            ".npz file"
        )
    return keys[0]


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


def _decoded(path, decode):
    """``decode()`` of a regular file, quietly, with any library's failure as one
    :class:`ImageError` line."""
    regular_file(path)
    try:
        with _quiet():
            return np.asarray(decode())
    except ImageError:
        raise
    except Exception as err:  # each library raises its own exception types
        raise _unreadable(path, err) from None


def integer_bits(path, *, channel: str | None = None) -> int | None:
    """The bits per sample of a render stored as integers, from the file's header: a PNG's
    bit depth, the dtype of a BlenderProc HDF5 file's integer ``colors``; None for a
    render stored as floats (EXR, PFM, a float NPY or HDF5 dataset) or in NPY/NPZ.

    Integer renders are display-referred: :func:`read_image` decodes them with
    ``transfer`` and ``scale``, and the import warns about their quantisation and clipping.
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


def read_image(
    path,
    *,
    transfer: str | None = None,
    scale: float = 1.0,
    out: np.ndarray | None = None,
    channel: str | None = None,
    view: int = 0,
) -> np.ndarray:
    """One render as float32 linear RGB, shape ``(H, W, 3)``.

    Parameters
    ----------
    path : path-like
        ``.exr`` (half or float, the R, G, B of its render layer or one grey channel, from
        any part), ``.pfm``, ``.png`` (8 or 16 bit), ``.npy`` or ``.npz`` (``(H, W, 3)``,
        ``(H, W, 4)`` or ``(H, W)``), or BlenderProc's ``.hdf5`` (its ``colors``: integer
        values are decoded as a PNG's, floats are linear).
    transfer : {"linear", "srgb"}, optional, keyword-only
        How integer values (PNG, BlenderProc's 8-bit colors) encode radiance (default
        ``srgb``); float formats are linear.
    scale : float, keyword-only
        Radiance of an integer value of full scale after the transfer function.
    out : numpy.ndarray, float32, shape (H, W, 3), optional, keyword-only
        Decode into this array (e.g. one slice of a stack of renders) instead of a new one.
    channel : str, optional, keyword-only
        EXR only (``audit.channels.render``): the layer whose R, G, B are the render
        (``ViewLayer.Combined``), or one grey channel; default: picked by name
        (:func:`~stereovar.io.channels.render_channels`). HDF5: the dataset.
    view : {0, 1}, keyword-only
        The view read from a file that holds both (BlenderProc's stereo HDF5: 0 left, 1
        right); a file of one view is read whatever it is.

    Returns
    -------
    numpy.ndarray, float32, shape (H, W, 3)
        ``out`` when given. Alpha is dropped; NaN and Inf are kept (the estimators count and
        exclude them).
    """
    fmt = image_format(path)
    if fmt in FIELD_ONLY:
        raise ImageError(
            f"{path}: a {fmt.upper()} file is read as a field (depth, disparity), not as a "
            "render; give the renders as EXR, PNG (Kubric's rgba_%05d.png), PFM, NPY or HDF5"
        )
    if out is not None:  # the header's size first: no decode of a file of another size
        height, width = image_size(path)
        if (height, width) != out.shape[:2]:
            raise ImageError(
                f"{path}: its header says {width}x{height} px but the other renders are "
                f"{out.shape[1]}x{out.shape[0]}; export every render at one resolution"
            )

    def decode():
        if fmt == "exr":
            return _exr_rgb(path, channel)
        if fmt == "pfm":
            return read_pfm(path)
        if fmt == "png":
            return _decode_png(*_png(path), transfer or "srgb", scale)
        if fmt == "hdf5":
            a = hdf5.read(path, role="render", view=view, channel=channel)
            return _decode_integer(a, path, transfer or "srgb", scale)
        return _array(path, fmt)

    a = _decoded(path, decode)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3 or a.shape[-1] not in (1, 3, 4):
        raise ImageError(
            f"{path}: an image has shape (H, W), (H, W, 3) or (H, W, 4), got {a.shape}; "
            "store one render per file"
        )
    a = a[..., :3] if a.shape[-1] >= 3 else np.broadcast_to(a, (*a.shape[:2], 3))
    if out is None:
        return np.ascontiguousarray(a, dtype=np.float32)
    if out.shape != a.shape:
        raise ImageError(
            f"{path}: {a.shape[1]}x{a.shape[0]} px but the other renders are "
            f"{out.shape[1]}x{out.shape[0]}; export every render at one resolution"
        )
    out[...] = a
    return out


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


def channel_names(fmt: str, count: int) -> list[str]:
    """The names of the ``count`` channels of a file of format ``fmt`` holding one value per
    pixel and channel, for error lines: ``R, G, B`` for a colour PNG, TIFF or PFM, their
    indices otherwise (an array's last axis).

    Parameters
    ----------
    fmt : str
        One of :data:`FORMATS`.
    count : int
        How many channels the file holds.

    Returns
    -------
    list of str

    Examples
    --------
    >>> channel_names("png", 3), channel_names("npy", 2)
    (['R', 'G', 'B'], ['0', '1'])
    """
    if fmt in ("png", "tiff", "pfm") and count == 3:
        return ["R", "G", "B"]
    return [str(k) for k in range(count)]


def one_field_channel(a: np.ndarray, path, what: str) -> np.ndarray:
    """The ``(H, W)`` values of a field decoded with a channel axis, ``(H, W, C)``: its one
    channel, or the first of channels that all hold the same values (a grey image saved as
    RGB). Channels that differ are refused: which of them holds the field, or whether the
    file is a colour-mapped picture of it, is not for the reader to guess.

    Parameters
    ----------
    a : numpy.ndarray, (H, W, C)
        The values as decoded (a PNG's or TIFF's colour channels in R, G, B order, alpha
        left out; an array's last axis).
    path : path-like
        The file, for the error line.
    what : str
        What the file was given as, in words (``"disparity"``, ``"a glass mask"``).

    Returns
    -------
    numpy.ndarray, (H, W)

    Raises
    ------
    ImageError
        Channels that differ (one line listing them and naming the fix).

    Examples
    --------
    >>> grey = np.arange(6.0).reshape(2, 3)
    >>> one_field_channel(np.stack([grey] * 3, axis=-1), "d.png", "disparity").tolist()
    [[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]]
    >>> one_field_channel(np.stack([grey, grey, 2 * grey], axis=-1), "d.png", "disparity")
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    stereovar.errors.ImageError: d.png: disparity given as 3 channels (R, G, B) that differ, ...
    """
    first = a[..., 0]
    nan = a.dtype.kind in "fc"
    if all(np.array_equal(first, a[..., k], equal_nan=nan) for k in range(1, a.shape[-1])):
        return first
    names = channel_names(image_format(path), a.shape[-1])
    plain = what.removeprefix("a ")
    raise ImageError(
        f"{path}: {what} given as {a.shape[-1]} channels ({', '.join(names)}) that differ, so "
        f"which of them holds the {plain}, or whether the file is a colour-mapped picture of "
        f"it, is not for the reader to guess; write the {plain} as one channel (a grey PNG or "
        "TIFF, or EXR, PFM or NPY)"
    )


def _one_channel(
    path, what: str, role: str | None, channel: str | None, view: int = 0
) -> np.ndarray:
    """The ``(H, W)`` values of a one-field file as stored (a PNG's integers or palette
    indices, an EXR channel's or a PFM's floats, an NPY's or HDF5 dataset's dtype): an EXR's
    channel or an HDF5 file's dataset holding ``role``; a file of several channels only when
    they are equal (:func:`one_field_channel`); ``what`` (``"a field"``) names it in the
    error line, or ``role`` does; ``view`` picks the view of an HDF5 file that holds both."""
    fmt = image_format(path)

    def decode():
        if fmt == "exr":
            return _exr_field(_exr_channels(path), path, role, channel)
        if fmt == "pfm":
            return read_pfm(path)
        if fmt == "png":
            if png_header(path)[1] == PNG_PALETTE:
                return _palette_indices(path)
            return _png(path)[0]
        if fmt == "hdf5":
            return hdf5.read(path, role=role, view=view, channel=channel)
        if fmt == "tiff":
            return _tiff(path)
        return _array(path, fmt)

    a = _decoded(path, decode)
    if a.ndim == 3:
        a = one_field_channel(a, path, WORDS.get(role, what))
    if a.ndim != 2:
        raise ImageError(f"{path}: {what} has shape (H, W), got {a.shape}; store one per file")
    return a


def read_field(
    path,
    *,
    png_scale: float | None = None,
    role: str | None = None,
    channel: str | None = None,
    view: int = 0,
) -> np.ndarray:
    """One scalar field (disparity, depth, a mask or a segmentation map) as float32 (H, W).

    Parameters
    ----------
    path : path-like
        ``.exr`` (its one channel, or the channel holding ``role``, from any part),
        ``.pfm`` (``Pf``; SceneFlow and Middlebury files), ``.png`` (8 or 16 bit, grey,
        or RGB with equal channels; a palette PNG's indices), ``.npy``, ``.npz``, ``.tiff``
        (one channel, or equal ones;
        :mod:`stereovar.audit.generators` says what a Kubric depth TIFF holds) or
        ``.hdf5`` (the dataset holding ``role``, :func:`stereovar.io.hdf5.field_layer`).
    png_scale : float, optional, keyword-only
        Divide PNG values by this (KITTI disparity: 256); default 1 (raw integer values).
    role : {"depth", "disparity", "segmentation", "glass_mask"}, optional, keyword-only
        What the field is, to pick an EXR's channel by name
        (:func:`~stereovar.io.channels.field_channel`: ``ViewLayer.Depth.Z`` is depth,
        ``ViewLayer.Combined.R`` never is); default: the one channel whose name means a
        field.
    channel : str, optional, keyword-only
        EXR and HDF5 (``audit.channels``): the channel's or dataset's name.
    view : {0, 1}, keyword-only
        The view read from an HDF5 file that holds both.

    Raises
    ------
    ImageError
        The file cannot be read, or no channel, or more than one, holds ``role`` (one line
        listing the channels and naming the fix).
    """
    a = _one_channel(path, "a field", role, channel, view)
    if image_format(path) == "png":
        a = a.astype(np.float64) / float(png_scale or 1.0)
    with np.errstate(over="ignore"):  # beyond float32 (Infinigen's DBL_MAX for no hit): inf
        return np.asarray(a, dtype=np.float32)


def _one_id_per_pixel(path) -> None:
    """Refuse an NPY segmentation with several values per pixel (Infinigen's
    ``InstanceSegmentation_*.npy``, ``(H, W, 3)``: which of its values is the segment is
    not for the reader to guess), from its header."""
    if image_format(path) != "npy":
        return
    with open_regular(path) as f:
        try:
            shape = _npy_header(f)[0]
        except Exception as err:  # numpy raises its own exception types
            raise _unreadable(path, err, "header") from None
    if len(shape) == 3 and shape[-1] > 1:
        raise ImageError(
            f"{path}: a segmentation of shape {tuple(shape)}, {shape[-1]} values per pixel, "
            "and which one is the segment id is not for the reader to guess; give one id per "
            "pixel, (H, W) (Infinigen: ObjectSegmentation_*.npy, not InstanceSegmentation)"
        )


def read_labels(path, *, channel: str | None = None, view: int = 0) -> np.ndarray:
    """A segmentation map's segment ids as int64 ``(H, W)``, never through a float.

    Integer files keep their ids exactly: PNG (8 or 16 bit, one channel or equal ones; a
    palette PNG's indices, as Kubric's ``segmentation_%05d.png`` stores its ids), an EXR
    ``UINT`` channel, an integer NPY or NPZ (Infinigen's ``ObjectSegmentation_*.npy``), a
    BlenderProc ``*_segmaps`` dataset. Float files (an EXR ``HALF`` or ``FLOAT`` channel such
    as Blender's ``IndexOB``, PFM, a float NPY) tell whole numbers apart only below
    :math:`2^{p}` (:math:`p` the mantissa bits plus one: :math:`2^{24}` = 16777216 for
    float32, 2048 for half; :math:`2^{p} + 1` is stored as :math:`2^{p}`): their values are
    rounded, and a file holding an id of :math:`2^{p}` or more is refused, since two ids
    there can be stored as one; NaN and Inf read as -1 (no segment).

    Parameters
    ----------
    path : path-like
        ``.png``, ``.exr`` (its one channel, or the channel holding the segmentation,
        :func:`~stereovar.io.channels.field_channel`), ``.pfm``, ``.npy`` or ``.npz``.
    channel : str, optional, keyword-only
        EXR and HDF5 (``audit.channels.segmentation``): the channel's or dataset's name.
    view : {0, 1}, keyword-only
        The view read from an HDF5 file that holds both.

    Returns
    -------
    numpy.ndarray, int64, shape (H, W)
        The segment id of every pixel; -1 where a float file holds NaN or Inf.

    Raises
    ------
    ImageError
        The file cannot be read, is not one ``(H, W)`` map, holds no numbers, or holds float
        ids beyond what its float type tells apart (one line naming the fix).
    """
    _one_id_per_pixel(path)
    a = _one_channel(path, "a segmentation map", "segmentation", channel, view)
    if a.dtype.kind in "biu":
        return a.astype(np.int64)
    if a.dtype.kind != "f":
        raise ImageError(
            f"{path}: segment ids of type {a.dtype}; store them as integers (16-bit PNG, EXR "
            "UINT or an integer .npy)"
        )
    exact = 2 ** (np.finfo(a.dtype).nmant + 1)
    with np.errstate(invalid="ignore"):
        beyond = np.isfinite(a) & (np.abs(a) >= exact)
    if beyond.any():
        raise ImageError(
            f"{path}: segment ids up to {np.nanmax(np.abs(a[beyond])):.0f} stored as "
            f"{a.dtype}, which tells whole numbers apart only below {exact} ({exact + 1} is "
            f"stored as {exact}), so two ids there can read as one; write the segmentation as "
            "integers (EXR UINT, 16-bit PNG or an integer .npy)"
        )
    return np.rint(np.where(np.isfinite(a), a, -1.0)).astype(np.int64)  # NaN, Inf: no id


def write_image(
    path, image, *, transfer: str = "linear", scale: float = 1.0, half: bool = False
) -> None:
    """Write one ``(H, W, 3)`` linear RGB image in the format of ``path``'s extension.

    EXR is float (``half``: 16-bit float) with ZIP compression; PNG is 16 bit, ``image /
    scale`` encoded with ``transfer`` and clipped to [0, 1]; PFM, NPY and NPZ are float32.
    """
    fmt = image_format(path)
    a = np.asarray(image, dtype=np.float32)
    if a.ndim != 3 or a.shape[-1] != 3:
        raise ValueError(f"an image is (H, W, 3), got {a.shape}")
    if fmt == "exr":
        _write_exr(path, {c: a[..., k] for k, c in enumerate("RGB")}, half=half)
    elif fmt == "png":
        import cv2

        v = np.clip(a.astype(np.float64) / scale, 0.0, 1.0)
        if transfer == "srgb":
            v = linear_to_srgb(v)
        q = np.round(v * 65535.0).astype(np.uint16)
        if not cv2.imwrite(str(path), np.ascontiguousarray(q[..., ::-1])):
            raise OSError(f"{path}: OpenCV could not write it")
    else:
        _write_plain(path, a, fmt)


def write_field(path, field, *, png_scale: float = 256.0) -> None:
    """Write one ``(H, W)`` field: EXR (one float channel ``Z``), PFM (``Pf``), NPY, NPZ, or
    PNG as uint16 ``round(field * png_scale)`` (the KITTI disparity encoding, 0 = invalid)."""
    fmt = image_format(path)
    a = np.asarray(field, dtype=np.float32)
    if a.ndim != 2:
        raise ValueError(f"a field is (H, W), got {a.shape}")
    if fmt == "exr":
        _write_exr(path, {"Z": a})
    elif fmt == "png":
        import cv2

        with np.errstate(invalid="ignore"):
            q = np.where(np.isfinite(a) & (a > 0), np.round(a * png_scale), 0)
        if not cv2.imwrite(str(path), np.clip(q, 0, 65535).astype(np.uint16)):
            raise OSError(f"{path}: OpenCV could not write it")
    else:
        _write_plain(path, a, fmt)


def _write_exr(path, channels: dict, *, half: bool = False) -> None:
    import OpenEXR

    dtype = np.float16 if half else np.float32
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    pixels = {k: np.ascontiguousarray(v, dtype=dtype) for k, v in channels.items()}
    with OpenEXR.File(header, pixels) as f:
        f.write(str(path))


def _write_plain(path, a, fmt) -> None:
    if fmt == "pfm":
        write_pfm(path, a)
    elif fmt == "npy":
        with open(path, "wb") as f:
            np.save(f, a)
    else:
        with open(path, "wb") as f:
            np.savez_compressed(f, a)
