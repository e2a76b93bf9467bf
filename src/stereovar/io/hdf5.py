"""BlenderProc's HDF5 output (``0.hdf5``, ``1.hdf5``, ...), read by what its datasets mean.

BlenderProc writes one HDF5 file per frame with one dataset per output key
(``blenderproc/python/writer/WriterUtility.py`` of DLR-RM/BlenderProc, commit a80f75d, 2025:
``write_hdf5``, lines 25-93, and ``_WriterUtility.write_to_hdf_file``, lines 344-365, which
stores arrays gzip-compressed and strings as bytes):

==========================  ===================================================================
dataset                     holds
==========================  ===================================================================
``colors``                  the render: ``uint8`` (its default: an 8-bit PNG through Blender's
                            view transform, ``DefaultConfig.file_format = "PNG"``,
                            ``color_depth = 8``, ``view_transform = "Filmic"``,
                            ``blenderproc/python/utility/DefaultConfig.py`` lines 26-27 and 44),
                            ``uint16`` (16-bit PNG) or ``float32`` (``OPEN_EXR``, linear), read
                            with OpenCV through imageio as RGB (``load_image``,
                            ``blenderproc/python/utility/BlenderUtility.py`` lines 144-157)
``depth``                   planar depth in m: Blender's Z pass
                            (``enable_depth_output``, ``renderer/RendererUtility.py`` lines
                            260-325; with antialiasing the mist pass converted by
                            ``dist2depth``, ``postprocessing/PostProcessingUtility.py`` lines
                            15-43), one channel after ``trim_redundant_channels``
``distance``                the distance along the camera ray (``enable_distance_output``,
                            lines 179-257): not planar depth, and the file stores no camera
                            intrinsics to convert it with, so it is refused as depth
``*_segmaps``               segment ids (``instance_segmaps``, ``class_segmaps``, ...)
``normals``, ``diffuse``    not read
==========================  ===================================================================

A stereo render (Blender multiview, ``bproc.renderer.toggle_stereo(True)``) stores each key
as one array with a leading axis of 2, ``[0]`` the left view and ``[1]`` the right
(``load_registered_outputs``, WriterUtility.py lines 115-124: "output_file[0] is the left
image and output_file[1] the right image"), or, with ``stereo_separate_keys=True``, as
``<key>_0`` and ``<key>_1`` (lines 76-84). A dataset is picked by what its name means
(:mod:`stereovar.io.channels`: ``colors`` is the render, ``depth`` depth, ``distance`` ray
distance, ``*_segmaps`` a segmentation), never by position; a file where that is ambiguous
is refused with one line listing its datasets, and ``audit.channels`` names one.

h5py is imported on first use; without it the reader stops with one line naming the package.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ..errors import ImageError
from .channels import field_channel, foreign_channel, listing, normalised

RENDER_NAMES = frozenset({"colors", "color", "rgb", "rgba", "image", "combined"})
"""Dataset names (normalised, :func:`~stereovar.io.channels.normalised`) that hold a render."""

VIEW_SUFFIX = re.compile(r"^(?P<base>.+)_(?P<view>[01])$")
"""``<key>_0`` and ``<key>_1``: the left and right view of ``<key>``
(``write_hdf5(..., stereo_separate_keys=True)``)."""


def h5py_module():
    """``h5py``, or one :class:`~stereovar.errors.ImageError` line naming the package."""
    try:
        import h5py
    except ImportError:
        raise ImageError(
            "reading HDF5 files (BlenderProc's output) needs h5py, a dependency of stereovar; "
            "install it: pip install h5py"
        ) from None
    return h5py


@dataclass(frozen=True)
class Layer:
    """One output of a BlenderProc file: its name, the datasets holding it (one, or one per
    view), whether its one dataset stacks both views on a leading axis of 2, and the shape
    and dtype of one view."""

    name: str
    keys: tuple
    stacked: bool
    shape: tuple
    dtype: np.dtype

    @property
    def views(self) -> int:
        """1 (one view) or 2 (both views)."""
        return 2 if self.stacked or len(self.keys) == 2 else 1

    @property
    def size(self) -> tuple[int, int]:
        """``(height, width)`` of one view."""
        return int(self.shape[0]), int(self.shape[1])


def _view_shape(shape: tuple) -> tuple[tuple, bool] | None:
    """The shape of one view of an array and whether it stacks two views: ``(H, W)`` or
    ``(H, W, C)`` (C in 1, 3, 4) for one view, the same with a leading axis of 2 for two.
    None for an array that is not an image (a vector, a matrix of numbers).

    Examples
    --------
    >>> _view_shape((4, 6)), _view_shape((2, 4, 6)), _view_shape((2, 4, 6, 3))
    (((4, 6), False), ((4, 6), True), ((4, 6, 3), True))
    >>> _view_shape((4, 6, 3)), _view_shape((3, 3)), _view_shape((7,))
    (((4, 6, 3), False), ((3, 3), False), None)
    """
    if len(shape) == 2:
        return shape, False
    if len(shape) == 3 and shape[0] == 2:
        return shape[1:], True
    if len(shape) == 3 and shape[-1] in (1, 3, 4):
        return shape, False
    if len(shape) == 4 and shape[0] == 2 and shape[-1] in (1, 3, 4):
        return shape[1:], True
    return None


def layers_of(datasets: dict) -> dict:
    """The image outputs of a BlenderProc file from its datasets' shapes and dtypes.

    Parameters
    ----------
    datasets : dict
        Dataset name to ``(shape, dtype)`` (numeric datasets only).

    Returns
    -------
    dict
        Output name to :class:`Layer`; ``<key>_0`` and ``<key>_1`` of one shape and dtype
        become one two-view layer ``<key>``. Datasets that are not images (fewer than two
        dimensions, a string) are left out.

    Examples
    --------
    >>> f32 = np.dtype("float32")
    >>> found = layers_of({"colors": ((2, 4, 6, 3), np.dtype("uint8")),
    ...                    "depth_0": ((4, 6), f32), "depth_1": ((4, 6), f32)})
    >>> [(k, v.views, v.size) for k, v in found.items()]
    [('colors', 2, (4, 6)), ('depth', 2, (4, 6))]
    """
    out = {}
    paired = set()
    for name, (shape, dtype) in sorted(datasets.items()):
        m = VIEW_SUFFIX.match(name)
        if m and m.group("view") == "0":
            other = f"{m.group('base')}_1"
            if other in datasets and datasets[other] == (shape, dtype):
                view = _view_shape(tuple(shape))
                if view is not None and not view[1]:
                    out[m.group("base")] = Layer(
                        m.group("base"), (name, other), False, view[0], np.dtype(dtype)
                    )
                    paired |= {name, other}
    for name, (shape, dtype) in sorted(datasets.items()):
        if name in paired or name in out:
            continue
        view = _view_shape(tuple(shape))
        if view is not None:
            out[name] = Layer(name, (name,), view[1], view[0], np.dtype(dtype))
    return dict(sorted(out.items()))


def _datasets_of(f) -> dict:
    """Numeric datasets of an open HDF5 file (groups descended): name to ``(shape,
    dtype)``; nothing is decoded."""
    found = {}

    def visit(name, obj):
        dtype = getattr(obj, "dtype", None)
        if dtype is not None and dtype.kind in "biuf":
            found[name] = (tuple(obj.shape), dtype)

    f.visititems(visit)
    return found


def layers(path) -> dict:
    """:func:`layers_of` the datasets of the HDF5 file at ``path`` (header only)."""
    with h5py_module().File(str(path), "r") as f:
        return layers_of(_datasets_of(f))


def size(path) -> tuple[int, int]:
    """``(height, width)`` of a BlenderProc file's outputs, from the datasets' shapes.

    Raises
    ------
    ImageError
        No image dataset, or outputs of different sizes (one line).
    """
    found = layers(path)
    if not found:
        raise ImageError(
            f"{path}: no image dataset in this HDF5 file; give BlenderProc's output "
            "(bproc.writer.write_hdf5), whose colors, depth and *_segmaps are images"
        )
    sizes = {layer.size for layer in found.values()}
    if len(sizes) > 1:
        shown = ", ".join(f"{k} {v.size[1]}x{v.size[0]}" for k, v in found.items())
        raise ImageError(
            f"{path}: its datasets differ in size ({shown}); write every output at one "
            "resolution"
        )
    return next(iter(sizes))


def render_layer(found: dict, path, channel: str | None = None) -> Layer:
    """The layer of a BlenderProc file that holds the render.

    Parameters
    ----------
    found : dict
        The file's :func:`layers`.
    path : path-like
        The file, for the error line.
    channel : str, optional
        ``audit.channels.render``: the dataset's name (without ``_0``/``_1``).

    Raises
    ------
    ImageError
        The named dataset is missing; no dataset, or several, are named as a render with
        three or four channels (one line listing the datasets).

    Examples
    --------
    >>> found = layers_of({"colors": ((4, 6, 3), np.dtype("uint8")),
    ...                    "normals": ((4, 6, 3), np.dtype("float32"))})
    >>> render_layer(found, "0.hdf5").name
    'colors'
    """
    if channel is not None:
        if channel not in found:
            raise ImageError(
                f"{path}: audit.channels.render is {channel!r} but the file has no such "
                f"dataset (it has {listing(found)}); set audit.channels.render to one of them"
            )
        picked = [channel]
    else:
        picked = [k for k in found if normalised(k) in RENDER_NAMES]
    if len(picked) == 1:
        layer = found[picked[0]]
        if len(layer.shape) != 3 or layer.shape[-1] not in (3, 4):
            if channel is None:
                foreign_channel(picked[0], "render", path)
            raise ImageError(
                f"{path}: dataset {picked[0]!r} has {layer.shape} per view, not (H, W, 3) or "
                "(H, W, 4); give the colors dataset"
            )
        return layer
    what = "several datasets" if picked else "no dataset"
    raise ImageError(
        f"{path}: {what} of this HDF5 file hold{'s' * (not picked)} a render "
        f"({listing(picked or found)}); set audit.channels: {{render: <one of them>}}"
    )


def field_layer(found: dict, role: str | None, path, channel: str | None = None) -> Layer:
    """The layer of a BlenderProc file that holds the field ``role``, picked by name as an
    EXR channel is (:func:`~stereovar.io.channels.field_channel`: ``depth`` is depth,
    ``distance`` ray distance and refused, ``*_segmaps`` a segmentation; one output only:
    that one, unless its name says it holds something else).

    Examples
    --------
    >>> f32 = np.dtype("float32")
    >>> found = layers_of({"colors": ((4, 6, 3), np.dtype("uint8")), "depth": ((4, 6), f32),
    ...                    "instance_segmaps": ((4, 6), np.dtype("uint8"))})
    >>> [field_layer(found, role, "0.hdf5").name for role in ("depth", "segmentation")]
    ['depth', 'instance_segmaps']
    """
    name = field_channel(list(found), role, path, channel)
    layer = found[name]
    if len(layer.shape) == 3 and layer.shape[-1] != 1:
        raise ImageError(
            f"{path}: dataset {name!r} has {layer.shape[-1]} channels per view, not one; "
            "give a one-channel field (BlenderProc trims depth and distance to one)"
        )
    return layer


def _slice(f, layer: Layer, view: int) -> np.ndarray:
    """One view of a layer (view 0 of a one-view layer whatever ``view`` is)."""
    if len(layer.keys) == 2:
        return np.asarray(f[layer.keys[view]])
    if layer.stacked:
        return np.asarray(f[layer.keys[0]][view])
    return np.asarray(f[layer.keys[0]])


def read(path, *, role: str | None, view: int = 0, channel: str | None = None) -> np.ndarray:
    """One view of the output of a BlenderProc file that holds ``role``, as stored.

    Parameters
    ----------
    path : path-like
    role : {"render", "depth", "disparity", "segmentation", "glass_mask"} or None
        What to read: the render (:func:`render_layer`) or a field (:func:`field_layer`;
        None: the one output whose name means a field).
    view : {0, 1}, keyword-only
        The view of a two-view output (0 left, 1 right); a one-view output is read whatever
        it is.
    channel : str, optional, keyword-only
        ``audit.channels``: the dataset's name.

    Returns
    -------
    numpy.ndarray
        ``(H, W, C)`` for the render, ``(H, W)`` for a field, in the dataset's dtype.
    """
    h5py = h5py_module()
    with h5py.File(str(path), "r") as f:
        found = layers_of(_datasets_of(f))
        layer = (
            render_layer(found, path, channel)
            if role == "render"
            else field_layer(found, role, path, channel)
        )
        a = _slice(f, layer, view)
    return a[..., 0] if role != "render" and a.ndim == 3 else a


def render_views(path, channel: str | None = None) -> int:
    """How many views (1 or 2) the render of a BlenderProc file holds (header only)."""
    return render_layer(layers(path), path, channel).views


def render_dtype(path, channel: str | None = None) -> np.dtype:
    """The dtype of the render of a BlenderProc file (header only)."""
    return render_layer(layers(path), path, channel).dtype
