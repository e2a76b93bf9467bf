"""Reading the image files other tools write: OpenEXR, PFM, PNG (8 and 16 bit), NPY, NPZ,
and the generators' own formats: BlenderProc's HDF5 and Kubric's float TIFF.

The audit (:mod:`stereovar.audit`) reads renders, disparity, depth and masks made elsewhere
through :func:`read_image`, :func:`read_field` and :func:`read_labels`; the export writes
ours through :func:`~stereovar.io.writers.write_image` and
:func:`~stereovar.io.writers.write_field`. The readers return float32 (images:
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
refused by its kind before it is opened for reading
(:func:`~stereovar.io.files.regular_file`), so nothing waits on a pipe that no one writes to.
What the libraries print themselves about a damaged file (OpenEXR's and libpng's diagnostics)
is silenced; the :class:`ImageError` says it once.

This module holds the readers; the rest of the image files' code lives beside it:
:mod:`stereovar.io.formats` (the formats by extension), :mod:`stereovar.io.transfer` (the sRGB
transfer function), :mod:`stereovar.io.files` (regular files only, the one-line errors),
:mod:`stereovar.io.headers` (what a header says: size, half floats, integer bits),
:mod:`stereovar.io.decoders` (each format's pixels), :mod:`stereovar.io.pfm` (PFM by hand) and
:mod:`stereovar.io.writers` (:func:`~stereovar.io.writers.write_image`,
:func:`~stereovar.io.writers.write_field`).
"""

from __future__ import annotations

import numpy as np

from ..errors import ImageError
from . import hdf5
from .channels import WORDS
from .decoders import (
    _array,
    _decode_integer,
    _decode_png,
    _exr_channels,
    _exr_field,
    _exr_rgb,
    _palette_indices,
    _png,
    _tiff,
)
from .files import _quiet, _unreadable, open_regular, regular_file
from .formats import FIELD_ONLY, image_format
from .headers import PNG_PALETTE, _npy_header, image_size, png_header
from .pfm import read_pfm


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



def channel_names(fmt: str, count: int) -> list[str]:
    """The names of the ``count`` channels of a file of format ``fmt`` holding one value per
    pixel and channel, for error lines: ``R, G, B`` for a colour PNG, TIFF or PFM, their
    indices otherwise (an array's last axis).

    Parameters
    ----------
    fmt : str
        One of :data:`~stereovar.io.formats.FORMATS`.
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

