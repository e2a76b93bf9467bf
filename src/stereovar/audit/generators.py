"""The generators' own ground truth, read by what it means: Kubric's depth TIFF with its
``metadata.json``, Infinigen's frame folders with their ``camview`` files.

The audit's depth is planar depth :math:`z` (the distance along the optical axis), never a
distance along the camera ray; a generator whose depth is the latter is converted with the
camera its own files store, or refused.

**Kubric** (google-research/kubric, commit 0ee21e2, 2024) writes ``depth_%05d.tiff``
(float32, one channel, through imageio: ``kubric/file_io.py`` lines 189-196 and 266-269),
``rgba_%05d.png`` (8-bit, Blender's view transform) and ``segmentation_%05d.png`` (a palette
PNG whose indices are the segment ids: lines 120-143 and 272-279) per frame, and
``metadata.json`` beside them (``challenges/movi/movi_c_worker.py`` lines 221-227) with the
camera's ``focal_length`` and ``sensor_width`` in mm (``kubric/utils.py`` lines 145-156) and
the scene's ``resolution`` (lines 132-142). Its depth is the distance from the camera centre:
``process_depth`` turns Blender's Z pass into it ("blender returns z values (distance to
camera plane) / convert them into depth (distance to camera center)",
``kubric/renderer/blender_utils.py`` lines 429-432) with ``PerspectiveCamera.z_to_depth``
(``kubric/core/cameras.py`` lines 154-169),

.. math::

    r = z \\sqrt{1 + \\frac{u^2 + v^2}{f_{mm}^2}}, \\qquad
    u = \\Bigl(i + \\tfrac12 - \\tfrac W2\\Bigr) \\frac{s_w}{W}, \\quad
    v = \\Bigl(j + \\tfrac12 - \\tfrac H2\\Bigr) \\frac{s_w}{W},

(:math:`s_w` the sensor width, the sensor height :math:`s_w H / W`), which
:func:`kubric_planar_depth` inverts. A TIFF depth without Kubric's ``metadata.json`` beside it
is refused: nothing says whether it is planar or ray distance.

**Infinigen** (princeton-vl/infinigen, commit 25a7d28, 2026) names its outputs
``<Pass>_<rig>_<resample>_<frame>_<subcam>.<ext>`` (``src/infinigen/tools/suffixes.py``
lines 9-28) and files them as ``frames/<Pass>/camera_<subcam>/``
(``src/infinigen/tools/datarelease_toolkit.py`` lines 314-337): ``Image`` (PNG or EXR),
``Depth`` (``.npy``), ``ObjectSegmentation`` (``.npy``, int32 ids), and ``camview``
(``.npz`` with ``K`` in pixels, ``T`` the camera-to-world pose with OpenCV axes, x right, y
down, z forward, and ``HW``: ``src/infinigen/core/placement/camera.py`` lines 834-866). Its
depth is planar: the camera-space :math:`z` of the hit point (OpenGL ground truth,
``src/infinigen/datagen/customgt/main.cpp`` lines 399-419; its own ``rigid_warp`` unprojects
it as :math:`z\\,K^{-1}(x, y, 1)^T`, ``src/infinigen/tools/ground_truth/rigid_warp.py`` line
46), at twice the image size (``main.cpp`` lines 200-205; "Depth is stored as a 2H x 2W
32-bit floating point numpy array", ``docs/source/GroundTruthAnnotations.md`` line 92) with
``DBL_MAX`` where nothing is hit. Such a depth is brought to the image size as Infinigen's
own tool does (``cv2.resize`` with linear interpolation, ``rigid_warp.py`` line 75: at
exactly half the size, the mean of each 2x2 block; :func:`downsample_2x`). A stereo rig is
two sub-cameras; the ``camview`` files of both views give the focal length
(:math:`K_{00}`), the baseline and which camera is to the right
(:func:`stereo_geometry`).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import AuditError, ImageError
from ..io.formats import image_format
from ..io.headers import image_size
from ..io.images import read_field

KUBRIC_FILE = re.compile(r"^(depth|rgba|rgb|segmentation|normal|object_coordinates)_\d+\.")
"""A Kubric output's file name (``depth_00000.tiff``, ``rgba_00000.png``, ...)."""

KUBRIC_METADATA = "metadata.json"
"""Kubric's per-scene metadata, beside its images."""

INFINIGEN_FILE = re.compile(r"^(?P<kind>[A-Za-z]+)(?P<suffix>(_\d+){4})\.(png|exr|npy|npz)$")
"""An Infinigen output's file name: ``<Pass>_<rig>_<resample>_<frame>_<subcam>.<ext>``."""

RECTIFIED = 1e-3
"""Largest share of the baseline that the sub-cameras of a rig may be offset off the image's
x axis (up or forward), and largest angle in radians between their orientations, for the rig
to be read as a rectified pair."""

FOCAL_AGREEMENT = 1e-3
"""Largest relative difference between ``audit.focal_px`` or ``audit.baseline_m`` and what
the generator's own camera files say, and between the two views' focal lengths."""


@dataclass(frozen=True)
class Camera:
    """One view's camera as a generator's file states it.

    ``focal_px`` is the horizontal focal length in pixels at the image size ``size``
    (``(height, width)``); ``pose`` the camera-to-world matrix with OpenCV axes (Infinigen),
    or None (Kubric stores none per image); ``mm`` Kubric's focal length and sensor width
    in mm (None for Infinigen)."""

    generator: str
    path: Path
    focal_px: float
    size: tuple
    pose: np.ndarray | None = None
    mm: tuple | None = None


def camera_file(path) -> Path | None:
    """The file beside a generator's output that states its camera, found by the
    generator's naming (no file is opened): Kubric's ``metadata.json`` in the folder of a
    ``depth_%05d.tiff`` (or ``rgba_``, ``segmentation_`` ...), Infinigen's
    ``frames/camview/camera_<subcam>/camview_<suffix>.npz`` of a
    ``frames/<Pass>/camera_<subcam>/<Pass>_<suffix>.<ext>`` (or ``camview_<suffix>.npz`` in
    the same folder, the layout before Infinigen files its outputs by pass). None when
    there is none.

    Examples
    --------
    >>> import tempfile
    >>> root = Path(tempfile.mkdtemp())
    >>> (root / "frames/camview/camera_1").mkdir(parents=True)
    >>> (root / "frames/camview/camera_1/camview_0_0_0048_1.npz").touch()
    >>> camera_file(root / "frames/Depth/camera_1/Depth_0_0_0048_1.npy").relative_to(root)
    PosixPath('frames/camview/camera_1/camview_0_0_0048_1.npz')
    >>> camera_file(root / "elsewhere/depth.npy") is None
    True
    """
    path = Path(path)
    filed = infinigen_camview(path)
    if filed is not None:
        for candidate in (filed, path.parent / filed.name):
            if candidate.is_file():
                return candidate
    if KUBRIC_FILE.match(path.name) and (path.parent / KUBRIC_METADATA).is_file():
        return path.parent / KUBRIC_METADATA
    return None


def infinigen_camview(path) -> Path | None:
    """Where Infinigen writes the ``camview`` file of one of its outputs, found by name
    alone (nothing is opened): ``frames/camview/camera_<subcam>/camview_<suffix>.npz`` for
    ``frames/<Pass>/camera_<subcam>/<Pass>_<suffix>.<ext>``.

    Parameters
    ----------
    path : path-like
        An output of Infinigen (``Depth_0_0_0048_0.npy``, ``Image_0_0_0048_1.exr``).

    Returns
    -------
    Path or None
        The camview's path (whether or not it is there); None for a file not named as
        Infinigen names its outputs.

    Examples
    --------
    >>> infinigen_camview("scene/frames/Depth/camera_0/Depth_0_0_0048_0.npy").as_posix()
    'scene/frames/camview/camera_0/camview_0_0_0048_0.npz'
    >>> infinigen_camview("renders/L/seed_000.exr") is None
    True
    """
    path = Path(path)
    m = INFINIGEN_FILE.match(path.name)
    if m is None:
        return None
    name = f"camview{m.group('suffix')}.npz"
    return path.parent.parent.parent / "camview" / path.parent.name / name


def _kubric_camera(path: Path) -> Camera:
    try:
        data = json.loads(path.read_text())
        camera = data["camera"]
        focal, sensor = float(camera["focal_length"]), float(camera["sensor_width"])
        width, height = (int(v) for v in data["metadata"]["resolution"])
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise ImageError(
            f"{path}: not Kubric's metadata.json ({type(err).__name__}: {err}); it needs "
            "camera.focal_length, camera.sensor_width and metadata.resolution "
            "(kubric.get_camera_info, kubric.get_scene_metadata) to convert Kubric's depth"
        ) from None
    if not (focal > 0 and sensor > 0 and width > 0 and height > 0):
        raise ImageError(
            f"{path}: camera focal_length {focal} mm, sensor_width {sensor} mm, resolution "
            f"{width}x{height}: none may be zero or negative"
        )
    return Camera("kubric", path, focal / sensor * width, (height, width), None, (focal, sensor))


def _infinigen_camera(path: Path) -> Camera:
    try:
        with np.load(path, allow_pickle=False) as z:
            K, T, HW = (np.asarray(z[k], dtype=np.float64) for k in ("K", "T", "HW"))
    except (OSError, ValueError, KeyError) as err:
        raise ImageError(
            f"{path}: not Infinigen's camview file ({type(err).__name__}: {err}); it holds "
            "K (3x3), T (4x4) and HW (infinigen.core.placement.camera.save_camera_parameters)"
        ) from None
    shaped = K.shape == (3, 3) and T.shape == (4, 4) and HW.shape == (2,)
    if shaped:
        _finite_camview(path, K, T, HW)
    if not shaped or not K[0, 0] > 0:
        raise ImageError(
            f"{path}: K {K.shape}, T {T.shape}, HW {HW.shape}: Infinigen's camview holds a 3x3 "
            "K with a positive focal length, a 4x4 T and HW (height, width)"
        )
    return Camera("infinigen", path, float(K[0, 0]), (int(HW[0]), int(HW[1])), T, None)


def _finite_camview(path: Path, K, T, HW) -> None:
    """Refuse a camview whose pose, intrinsics or image size hold NaN or Inf: it places no
    camera, and a baseline or focal length from it would be NaN (one line naming the
    file)."""
    bad = [
        (what, int((~np.isfinite(a)).sum()), a.size)
        for what, a in (("pose T", T), ("intrinsic matrix K", K), ("image size HW", HW))
        if not np.isfinite(a).all()
    ]
    if not bad:
        return
    held = ", ".join(f"a non-finite {what} ({n} of its {size} values NaN or Inf)"
                     for what, n, size in bad)
    raise ImageError(
        f"{path}: Infinigen's camview holds {held}, so it places no camera; export the "
        "frame's camview files again (infinigen.core.placement.camera.save_camera_parameters)"
    )


def read_camera(path) -> Camera:
    """The :class:`Camera` a Kubric ``metadata.json`` or an Infinigen ``camview_*.npz``
    states (:func:`camera_file` finds them).

    Raises
    ------
    ImageError
        The file is not what its name says, or a camview holds NaN or Inf (one line naming
        what it needs).
    """
    path = Path(path)
    if path.suffix == ".json":
        return _kubric_camera(path)
    return _infinigen_camera(path)


def kubric_planar_depth(distance, *, focal_mm: float, sensor_mm: float) -> np.ndarray:
    r"""Planar depth from Kubric's depth, the distance from the camera centre, by inverting
    ``PerspectiveCamera.z_to_depth`` (``kubric/core/cameras.py`` lines 154-169):

    .. math::

        z = \frac{r}{\sqrt{1 + (u^2 + v^2) / f_{mm}^2}}, \qquad
        u = \Bigl(i + \tfrac12 - \tfrac W2\Bigr)\frac{s_w}{W}, \quad
        v = \Bigl(j + \tfrac12 - \tfrac H2\Bigr)\frac{s_w}{W}.

    Parameters
    ----------
    distance : array_like (H, W)
        Kubric's ``depth_%05d.tiff``.
    focal_mm, sensor_mm : float, keyword-only
        The camera's ``focal_length`` and ``sensor_width`` (``metadata.json``).

    Returns
    -------
    numpy.ndarray, float64 (H, W)

    Examples
    --------
    >>> r = np.full((2, 2), 10.0)
    >>> z = kubric_planar_depth(r, focal_mm=1.0, sensor_mm=2.0)  # pixel centres at +-0.5 mm
    >>> np.allclose(z, 10.0 / np.sqrt(1.5))
    True
    """
    r = np.asarray(distance, dtype=np.float64)
    height, width = r.shape
    pitch = sensor_mm / width  # mm per pixel, both axes (sensor height = s_w H / W)
    u = (np.arange(width) + 0.5 - width / 2) * pitch
    v = (np.arange(height) + 0.5 - height / 2) * pitch
    scale = np.sqrt(1.0 + (u[None, :] ** 2 + v[:, None] ** 2) / focal_mm**2)
    return r / scale


def downsample_2x(depth) -> np.ndarray:
    r"""A depth map at twice the image size brought to the image size as Infinigen's
    ``rigid_warp`` does (``cv2.resize(..., INTER_LINEAR)`` to half the size): the mean of
    each 2x2 block,

    .. math:: z(x, y) = \tfrac14 \sum_{a, b \in \{0, 1\}} z_{2\times}(2x + a, 2y + b);

    a block touching Infinigen's ``DBL_MAX`` (no hit) or a non-finite value is NaN
    (invalid).

    Examples
    --------
    >>> downsample_2x(np.array([[1.0, 3.0], [5.0, 7.0]]))
    array([[4.]])
    """
    z = np.asarray(depth, dtype=np.float64)
    height, width = z.shape[0] // 2, z.shape[1] // 2
    blocks = z[: 2 * height, : 2 * width].reshape(height, 2, width, 2)
    with np.errstate(over="ignore", invalid="ignore"):
        finite = (np.isfinite(blocks) & (np.abs(blocks) < np.finfo(np.float32).max)).all((1, 3))
        mean = np.where(finite, blocks.mean(axis=(1, 3)), np.nan)
    return mean


def read_depth(path, *, size, camera: Camera | None = None, view: int = 0,
               channel: str | None = None) -> np.ndarray:
    """Planar depth in m from a depth file, by what the file and its generator say.

    Parameters
    ----------
    path : path-like
        The depth file: EXR, PFM, NPY, NPZ, PNG, BlenderProc's HDF5 (its ``depth``; its
        ``distance`` is refused), Kubric's TIFF (converted with ``camera``) or Infinigen's
        ``Depth_*.npy`` (at the image size, or twice it: :func:`downsample_2x`).
    size : tuple of int, keyword-only
        ``(height, width)`` of the frame's renders.
    camera : Camera, optional, keyword-only
        The generator's camera of this file (:func:`camera_file`, :func:`read_camera`).
    view : {0, 1}, keyword-only
        The view of an HDF5 file holding both.
    channel : str, optional, keyword-only
        ``audit.channels.depth``.

    Returns
    -------
    numpy.ndarray, float64 (H, W)
        NaN where the file holds no finite depth (nothing hit: Infinigen's ``DBL_MAX``).

    Raises
    ------
    ImageError
        A TIFF depth without Kubric's ``metadata.json``, a Kubric camera whose resolution is
        not the depth's, or a depth whose size is neither the renders' nor, for Infinigen,
        twice it (one line naming the choices).
    """
    fmt = image_format(path)
    if fmt == "tiff" and (camera is None or camera.generator != "kubric"):
        raise ImageError(
            f"{path}: a TIFF depth map says not whether it holds planar depth or the distance "
            "from the camera centre (Kubric's depth_%05d.tiff holds the latter); put Kubric's "
            "metadata.json beside it (its camera converts the distance to planar depth), or "
            "give planar depth as EXR, NPY or PFM"
        )
    z = np.asarray(read_field(path, role="depth", channel=channel, view=view), np.float64)
    if camera is not None and camera.generator == "kubric":
        if z.shape != tuple(camera.size):
            raise ImageError(
                f"{path}: {z.shape[1]}x{z.shape[0]} px but {camera.path} gives the resolution "
                f"{camera.size[1]}x{camera.size[0]}; give the metadata.json of this render"
            )
        if fmt == "tiff":
            z = kubric_planar_depth(z, focal_mm=camera.mm[0], sensor_mm=camera.mm[1])
    if z.shape == tuple(size):
        return np.where(np.isfinite(z), z, np.nan)  # inf, float32 overflow: nothing hit
    if (camera is not None and camera.generator == "infinigen"
            and z.shape == (2 * size[0], 2 * size[1])):
        return downsample_2x(z)
    raise ImageError(
        f"{path}: {z.shape[1]}x{z.shape[0]} px but the renders are {size[1]}x{size[0]}; give "
        "depth at the renders' size (or Infinigen's at twice it, with its camview file)"
    )


def depth_size(path, size) -> tuple[int, int]:
    """The size a depth file counts as in the frame's size check: its own, or the renders'
    ``size`` for an Infinigen depth at exactly twice it with its ``camview`` file found
    (:func:`read_depth` brings it to the renders' size)."""
    own = image_size(path)
    if (own == (2 * size[0], 2 * size[1]) and INFINIGEN_FILE.match(Path(path).name)
            and camera_file(path) is not None):
        return tuple(size)
    return own


@dataclass(frozen=True)
class StereoGeometry:
    """What two views' camera poses say: the baseline in m, the disparity sign :math:`s`
    of :math:`x_R = x_L + s\\,d` (-1: the right camera is to the right), and the files."""

    baseline_m: float
    sign: int
    files: tuple


def stereo_geometry(left: Camera, right: Camera) -> StereoGeometry:
    r"""The baseline and disparity sign of a rectified pair from its cameras' poses.

    With :math:`R_L, c_L` and :math:`R_R, c_R` the rotations and centres of the
    camera-to-world poses (OpenCV axes: x right, y down, z forward), the right camera's
    centre in the left camera's frame is :math:`t = R_L^T (c_R - c_L)`; the pair is
    rectified when :math:`R_L = R_R` (the angle of :math:`R_L^T R_R`,
    :math:`\arccos((\operatorname{tr} R_L^T R_R - 1) / 2)`, at most :data:`RECTIFIED`) and
    :math:`t` lies along x, and then

    .. math:: B = \lVert t \rVert, \qquad s = -\operatorname{sign}(t_x)

    (a right camera at :math:`+x` sees a point at :math:`x_R = x_L - f B / z`).

    Raises
    ------
    AuditError
        The poses are not a rectified pair, or the cameras coincide (one line).

    Examples
    --------
    >>> pose = np.eye(4)
    >>> moved = np.eye(4); moved[0, 3] = 0.075
    >>> cam = lambda T: Camera("infinigen", Path("c.npz"), 500.0, (4, 6), T)
    >>> g = stereo_geometry(cam(pose), cam(moved))
    >>> round(g.baseline_m, 6), g.sign
    (0.075, -1)
    """
    TL, TR = left.pose, right.pose
    t = TL[:3, :3].T @ (TR[:3, 3] - TL[:3, 3])
    baseline = float(np.linalg.norm(t))
    files = (str(left.path), str(right.path))
    if baseline == 0:
        raise AuditError(
            f"{files[0]} and {files[1]} place both cameras at one point; give the camview "
            "files of the two cameras of a stereo rig"
        )
    cosine = (np.trace(TL[:3, :3].T @ TR[:3, :3]) - 1.0) / 2.0
    turned = float(np.arccos(np.clip(cosine, -1.0, 1.0)))
    across = float(np.hypot(t[1], t[2]) / baseline)
    if turned > RECTIFIED or across > RECTIFIED:
        raise AuditError(
            f"{files[0]} and {files[1]}: the cameras are not a rectified pair (turned "
            f"{turned:.2g} rad apart, the second offset {across:.2g} of the baseline off the "
            "image's x axis), so depth gives no horizontal disparity; give audit.disparity"
        )
    return StereoGeometry(baseline, -1 if t[0] > 0 else 1, files)
