"""Decoding one frame of an audit: its size from the files' headers
(:func:`check_sizes`), its rig from the settings and the generator's camera files
(:func:`frame_optics`), its disparity, depth and glass (:func:`frame_fields`,
:func:`frame_glass`), and each view's renders into one stack (:func:`decode_view`), with the
checks and measures of what the renders can show (identical seeds, quantisation, clipping,
half floats).

Every file is read through :class:`~stereovar.audit.hashing.Reads`, so it is hashed as it
is decoded.
"""

from __future__ import annotations

import hashlib
import warnings
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import AuditError
from ..io.formats import image_format
from ..io.headers import image_size, stored_as_half
from ..io.images import read_field, read_image, read_labels
from ..rig import VIEWS
from .generators import (
    FOCAL_AGREEMENT,
    depth_size,
    infinigen_camview,
    read_camera,
    read_depth,
    stereo_geometry,
)
from .ground_truth import disparity_from_depth
from .hashing import Reads
from .layout import Frame
from .records import HALF_STEPS
from .settings import RELATIONS


def check_sizes(frame: Frame) -> tuple[int, int]:
    """The frame's size from its files' headers; a file whose header gives another size than
    most of the frame's files is named, before any file is decoded. An Infinigen depth at
    twice the renders' size counts as the renders' size
    (:func:`~stereovar.audit.generators.depth_size`)."""
    sizes = {path: image_size(path) for path in frame.images()}
    render_size = sizes[next(iter(frame.renders[VIEWS[0]].values()))]
    for path in frame.ground_truth.get("depth", {}).values():
        sizes[path] = depth_size(path, render_size)
        if sizes[path] == (2 * render_size[0], 2 * render_size[1]):
            _check_camviews(frame, path, render_size)
    size, count = Counter(sizes.values()).most_common(1)[0]  # a tie: the first render's
    for path, other in sizes.items():
        if other != size:
            others = (
                f"the frame's other {count} files are"
                if count == len(sizes) - 1
                else f"{count} of the frame's {len(sizes)} files are"
            )
            raise AuditError(
                f"{path} is {other[1]}x{other[0]} px but {others} {size[1]}x{size[0]} px; every "
                "render, disparity, depth and mask of a frame needs the same size: export them "
                "at one resolution"
            )
    return size


def _check_camviews(frame: Frame, depth, size) -> None:
    """Refuse an Infinigen depth at twice the renders' ``size`` whose ``camview`` files
    are missing (it is read at that size with them only): one line naming the camview
    files of the frame's views that are not there, where Infinigen writes them."""
    expected = infinigen_camview(depth)
    if expected is None:  # not Infinigen's: the size check names it
        return
    named = [expected]
    for view in VIEWS:
        if view not in frame.cameras:
            source = frame.ground_truth["depth"].get(view)
            named.append(infinigen_camview(source or next(iter(frame.renders[view].values()))))
    missing = [str(p) for p in dict.fromkeys(named) if p is not None and not p.is_file()]
    if not missing:
        return
    plural = "s" * (len(missing) != 1)
    raise AuditError(
        f"{depth} is {2 * size[1]}x{2 * size[0]} px, twice the renders' {size[1]}x{size[0]}: "
        f"Infinigen's depth, which is read with the frame's camview files, but the "
        f"camview file{plural} {' and '.join(missing)} {'are' if plural else 'is'} missing "
        "(Infinigen writes them to frames/camview/camera_<subcam>/ beside frames/Depth/); "
        "copy the scene's frames/camview folder along with the frame"
    )


@dataclass
class Optics:
    """What a frame's settings and its generator's camera files say about its rig: the
    focal length in px and baseline in m that turn depth into disparity (None: not
    known), the disparity sign the cameras' poses give (None: they give none), each view's
    :class:`~stereovar.audit.generators.Camera`, and where each number came from."""

    focal_px: float | None = None
    baseline_m: float | None = None
    sign: int | None = None
    cameras: dict = field(default_factory=dict)
    sources: dict = field(default_factory=dict)


def _agreeing(key: str, given, stated, where: str):
    """``audit.<key>`` when given, else what the camera files state; both given and more
    than :data:`~stereovar.audit.generators.FOCAL_AGREEMENT` apart are refused."""
    if given and stated and abs(given - stated) > FOCAL_AGREEMENT * stated:
        unit = "px" if key == "focal_px" else "m"
        raise AuditError(
            f"audit.{key} is {given:g} {unit} but {where} gives {stated:.6g} {unit}; "
            f"remove audit.{key} to use the generator's camera, or set it to {stated:.6g}"
        )
    return given or stated or None


def frame_optics(settings: dict, frame: Frame, size, reads) -> Optics:
    """The focal length, baseline and disparity sign of a frame from ``audit.focal_px``,
    ``audit.baseline_m`` and the generator's camera files (Kubric's ``metadata.json``:
    the focal length; Infinigen's ``camview`` of both views: the focal length, the baseline
    and which camera is to the right, :func:`~stereovar.audit.generators.stereo_geometry`).

    Raises
    ------
    AuditError
        A camera file of another image size, views with different focal lengths, a setting
        that disagrees with the files, or poses that are not a rectified pair (one line).
    """
    cameras = {v: reads(read_camera, p) for v, p in frame.cameras.items()}
    optics = Optics(cameras=cameras)
    for camera in cameras.values():
        if tuple(camera.size) != tuple(size):
            raise AuditError(
                f"{camera.path} gives the image size {camera.size[1]}x{camera.size[0]} but "
                f"the renders of frame {frame.name} are {size[1]}x{size[0]}; give the camera "
                "file of these renders"
            )
    focal = {v: c.focal_px for v, c in cameras.items()}
    if len(focal) == 2:
        left, right = focal["left"], focal["right"]
        if abs(left - right) > FOCAL_AGREEMENT * left:
            raise AuditError(
                f"{cameras['left'].path} gives a focal length of {left:.6g} px, "
                f"{cameras['right'].path} {right:.6g} px: the views are not a rectified pair; "
                "give audit.disparity"
            )
    stated_focal = next(iter(focal.values()), None)
    where = str(next(iter(cameras.values())).path) if cameras else ""
    optics.focal_px = _agreeing("focal_px", settings["focal_px"], stated_focal, where)
    stated_baseline = None
    posed = [c for c in cameras.values() if c.pose is not None]
    if len(posed) == 2:
        geometry = stereo_geometry(cameras["left"], cameras["right"])
        stated_baseline, optics.sign = geometry.baseline_m, geometry.sign
        where = " and ".join(geometry.files)
    optics.baseline_m = _agreeing("baseline_m", settings["baseline_m"], stated_baseline, where)
    optics.sources = {
        "focal_px": "audit.focal_px" if settings["focal_px"] else (where if focal else ""),
        "baseline_m": "audit.baseline_m" if settings["baseline_m"] else (
            where if stated_baseline else ""),
    }
    return optics


def check_geometry(settings: dict, frame: Frame, optics: Optics, sign: int) -> None:
    """Refuse a declared convention that the cameras' poses contradict."""
    if optics.sign is None or optics.sign == sign:
        return
    declared = settings["convention"]
    other = "conventional" if declared == "paper" else "paper"
    side = "right" if optics.sign == -1 else "left"
    files = " and ".join(str(c.path) for c in optics.cameras.values())
    raise AuditError(
        f"frame {frame.name}: the camera poses of {files} put the right view's camera "
        f"{optics.baseline_m:.4g} m to the {side} of the left one ({RELATIONS[optics.sign]}) "
        f"but audit.convention is {declared} ({RELATIONS[sign]}); set audit.convention: "
        f"{other}, or swap audit.views if the views are the other way round"
    )


def frame_fields(settings: dict, frame: Frame, size, optics: Optics, reads: Reads) -> tuple:
    """The frame's disparity and planar depth (view to ``(H, W)``): read from the files
    (depth through :func:`~stereovar.audit.generators.read_depth`), and each computed from
    the other with the focal length and baseline where it is not given (:math:`d = f B /
    z`)."""
    gt, channels = frame.ground_truth, settings["channels"]
    depth = {
        v: reads(read_depth, p, size=size, camera=optics.cameras.get(v),
                 view=VIEWS.index(v), channel=channels.get("depth"))
        for v, p in gt.get("depth", {}).items()
    }
    focal, baseline = optics.focal_px, optics.baseline_m
    if "disparity" in gt:
        scale, channel = settings["disparity_scale"], channels.get("disparity")
        disparity = {
            v: reads(read_field, p, png_scale=scale, role="disparity", channel=channel,
                     view=VIEWS.index(v))
            for v, p in gt["disparity"].items()
        }
    elif not (focal and baseline):
        known = [f"{k.replace('_', ' ')} from {optics.sources[k]}"
                 for k in ("focal_px", "baseline_m") if optics.sources.get(k)]
        missing = [f"audit.{k}" for k, v in (("focal_px", focal), ("baseline_m", baseline))
                   if not v]
        raise AuditError(
            f"audit.depth needs {' and '.join(missing)} to give disparity (d = f B / z"
            + (f"; the {', '.join(known)}" if known else "")
            + f"); set {'both' if len(missing) == 2 else 'it'}, or give audit.disparity"
        )
    else:
        disparity = {
            v: disparity_from_depth(z, focal_px=focal, baseline_m=baseline)
            for v, z in depth.items()
        }
    if not depth and focal and baseline:
        depth = {
            v: disparity_from_depth(d, focal_px=focal, baseline_m=baseline)
            for v, d in disparity.items()
        }
    return disparity, depth


def frame_glass(settings: dict, frame: Frame, reads: Reads):
    gt = frame.ground_truth
    if "glass_mask" in gt:
        path = gt["glass_mask"][VIEWS[0]]
        channel = settings["channels"].get("glass_mask")
        mask = reads(read_field, path, role="glass_mask", channel=channel)
        return mask > 0, f"glass mask {path}", None
    if "segmentation" in gt:
        ids = settings["glass_ids"]
        if not ids:
            raise AuditError(
                "audit.segmentation needs audit.glass_ids, the segment ids that are glass; "
                "list them (e.g. glass_ids: [3, 7])"
            )
        path = gt["segmentation"][VIEWS[0]]
        channel = settings["channels"].get("segmentation")
        seg = reads(read_labels, path, channel=channel)  # int64: ids above 2**24 stay apart
        glass = np.isin(seg, np.asarray(ids, dtype=np.int64))
        return glass, f"segmentation {path}", _unmatched_ids(seg, ids, path)
    return None, None, None


def _unmatched_ids(seg: np.ndarray, ids: list, path) -> str | None:
    """The warning for ``audit.glass_ids`` that match no pixel of a segmentation map."""
    present, counts = np.unique(seg, return_counts=True)
    missing = [i for i in ids if i not in present]
    if not missing:
        return None
    order = np.argsort(-counts, kind="stable")[:8]
    largest = ", ".join(f"{int(present[k])} ({int(counts[k])} px)" for k in order)
    return (
        f"audit.glass_ids {missing} match no pixel of {path}"
        + (" (so there is no glass region)" if len(missing) == len(ids) else "")
        + f"; the ids it holds, largest first: {largest}; fix audit.glass_ids"
    )


def integer_kind(frame: Frame, view: str) -> str:
    """``PNG`` or ``BlenderProc colors``: the kind of a view's integer renders, for the
    quantisation warning."""
    paths = frame.renders[view].values()
    return "PNG" if any(image_format(p) == "png" for p in paths) else "BlenderProc colors"


def seed_mean(stack: np.ndarray, n_nonfinite) -> np.ndarray:
    """Mean over seeds, skipping NaN/Inf (a plain float64 mean when every value is finite)."""
    if not np.any(n_nonfinite):
        return stack.mean(axis=0, dtype=np.float64)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN pixels stay NaN
        return np.nanmean(np.where(np.isfinite(stack), stack, np.nan), axis=0)


MIN_FINITE_PIXELS = 2
"""The fewest finite pixels a render, and a view's renders together, must hold: a
variance is measured only where every render is finite, and the camera law the
calibration fits to it (:func:`~stereovar.calibration.synthesis.camera_law`) needs two."""


def check_finite(stack: np.ndarray, n_nonfinite, frame: str, view: str, paths: list) -> None:
    """Refuse a render with fewer than :data:`MIN_FINITE_PIXELS` finite pixels (a render
    that is NaN or Inf everywhere failed), then a view whose renders are finite together at
    fewer: a pixel with a NaN or Inf in one render has no variance. A few NaN pixels
    import (the estimators count and leave them out).

    Parameters
    ----------
    stack : numpy.ndarray, (n, H, W, 3)
        The view's renders (:func:`decode_view`).
    n_nonfinite : array_like of int, (n,)
        Pixels with a NaN or Inf channel, per render.
    frame, view : str
        For the error line.
    paths : list
        The renders' files, in stack order.

    Raises
    ------
    AuditError
        One line naming the render (or the view) and its count of finite pixels.
    """
    n_nonfinite = np.asarray(n_nonfinite)
    if not n_nonfinite.any():
        return
    total = int(stack.shape[1] * stack.shape[2])
    for path, bad in zip(paths, n_nonfinite, strict=True):
        if total - int(bad) < MIN_FINITE_PIXELS:
            raise AuditError(
                f"{path}: {total - int(bad)} of its {total} pixels are finite (the others "
                f"hold NaN or Inf), and a render needs at least {MIN_FINITE_PIXELS} for any "
                "variance to be measured; render this seed again (a render that is NaN "
                "almost everywhere failed: check the renderer's output)"
            )
    finite = np.ones(stack.shape[1:3], dtype=bool)
    for image in stack:  # one render at a time: no temporary the size of the stack
        finite &= np.isfinite(image).all(axis=-1)
    together = int(finite.sum())
    if together < MIN_FINITE_PIXELS:
        worst = int(np.argmax(n_nonfinite))
        raise AuditError(
            f"frame {frame}, view {view}: {together} of the {total} pixels are finite in all "
            f"{len(paths)} renders (a pixel with a NaN or Inf in one render has no variance), "
            f"and the audit needs at least {MIN_FINITE_PIXELS}; render again the seeds whose "
            f"renders hold NaN or Inf (e.g. {paths[worst]}, {int(n_nonfinite[worst])} pixels)"
        )


def check_distinct(stack: np.ndarray, frame: str, view: str, paths: list) -> None:
    """Refuse renders of one view that are identical across seeds: the renderer was given
    one seed for them, and their variance is 0 (one line naming the seed settings)."""
    groups: dict = {}
    for k in range(stack.shape[0]):  # a sample of rows first, full equality to confirm
        key = hashlib.blake2b(np.ascontiguousarray(stack[k, ::7]).data, digest_size=16)
        groups.setdefault(key.digest(), []).append(k)
    same = []
    for members in groups.values():
        first = members[0]
        twins = [k for k in members[1:] if np.array_equal(stack[k], stack[first], equal_nan=True)]
        if twins:
            same.append([first, *twins])
    if not same:
        return
    n = stack.shape[0]
    which = (
        f"all {n} renders are identical"
        if len(same[0]) == n
        else f"{sum(len(g) for g in same)} of its {n} renders are copies of one another "
        f"(e.g. {Path(paths[same[0][0]]).name} and {Path(paths[same[0][1]]).name})"
    )
    raise AuditError(
        f"frame {frame}, view {view}: {which}: the renderer was given the same seed, so there "
        "is no Monte Carlo variance to measure; render each seed with its own sampler seed "
        "(Cycles: scene.cycles.seed, Mitsuba: mi.render(..., seed=...), Kubric and "
        "BlenderProc: the Cycles seed of each render) and import again"
    )


def clipped_fraction(stack: np.ndarray, valid: np.ndarray, scale: float) -> float:
    """Fraction of ``valid`` pixels at a PNG's full scale (``scale`` after decoding) in some
    render and channel: their variance is cut off."""
    clipped = (stack >= np.float32(scale)).any(axis=(0, 3))
    return float((clipped & valid).sum() / max(int(valid.sum()), 1))


def half_renders(stored: list, stack: np.ndarray) -> bool:
    """Whether a view's renders hold half-float (16-bit) values: as their files' headers
    say (``stored``: :func:`~stereovar.io.headers.stored_as_half` of each file, an EXR
    channel's pixel type or an NPY's dtype), so float32 renders whose values all happen to
    be half floats are not taken for half; only where no header says (PFM, None) by their
    values (:func:`_half_precision`)."""
    if False in stored:
        return False
    if None not in stored:
        return bool(stored)
    return _half_precision(stack)


def _half_precision(stack: np.ndarray) -> bool:
    """Whether every value of the renders is a half-float (16-bit) number: renders rounded
    to half precision before they were saved in a format whose header cannot say so (PFM).
    Float32 renders fail at their first render."""
    with np.errstate(over="ignore", invalid="ignore"):
        for image in stack:
            half = image.astype(np.float16).astype(np.float32)
            if not np.array_equal(half, image, equal_nan=True):
                return False
    return True


def half_quantised_fraction(stack: np.ndarray, valid: np.ndarray, mean: np.ndarray) -> float:
    r"""Fraction of ``valid`` pixels whose spread across the N renders is below
    :data:`HALF_STEPS` half-float steps in every channel:
    :math:`s_c(x) < k\,\Delta_{16}(\bar I_c(x))` for every channel :math:`c`, with
    :math:`s_c` the sample standard deviation over the seeds, :math:`\bar I_c` the seed
    mean ``mean`` (:func:`seed_mean`, float64 ``(H, W, 3)``), :math:`\Delta_{16}` the
    spacing of half floats there and :math:`k` = :data:`HALF_STEPS`. A pixel with a NaN or
    Inf render has no finite spread and is not counted."""
    squares = np.zeros_like(mean, dtype=np.float64)
    for image in stack:  # one render at a time: no temporary the size of the stack
        squares += (image - mean) ** 2
    spread = np.sqrt(squares / max(len(stack) - 1, 1))
    with np.errstate(over="ignore", invalid="ignore"):
        step = np.spacing(np.abs(mean).astype(np.float16)).astype(np.float64)
    coarse = (spread < HALF_STEPS * step).all(axis=-1)
    return float((coarse & valid).sum() / max(int(valid.sum()), 1))


def floored_fraction(stack: np.ndarray, valid: np.ndarray) -> float:
    """Fraction of ``valid`` pixels whose N renders are identical in every channel (their
    estimated variance is 0: quantisation floored it)."""
    same = (stack == stack[:1]).all(axis=(0, 3))
    return float((same & valid).sum() / max(int(valid.sum()), 1))


def _render(path, *, channel=None, **options) -> tuple:
    """A render (:func:`~stereovar.io.images.read_image`) and whether its file stores it as
    half floats (:func:`~stereovar.io.headers.stored_as_half`), in one verified read."""
    return read_image(path, channel=channel, **options), stored_as_half(path, channel=channel)


def decode_view(
    paths: list, size: tuple, pool, transfer, scale, reads: Reads, channel=None, view=0
) -> tuple:
    """Decode one view's renders into one ``(n, H, W, 3)`` float32 stack, each file straight
    into its slice by a worker thread, which also counts its NaN/Inf pixels and reads from
    its header whether it is stored as half floats; ``channel``: ``audit.channels.render``,
    the EXR layer or HDF5 dataset of the render; ``view``: the view (0 left, 1 right) read
    from a file that holds both.

    Returns
    -------
    stack : numpy.ndarray, float32, (n, H, W, 3)
    n_nonfinite : numpy.ndarray, int64, (n,)
        Pixels with a NaN or Inf channel, per render.
    stored : list of bool or None
        Per render, whether its file stores half floats (None: its header cannot say).
    """
    stack = np.empty((len(paths), *size, 3), dtype=np.float32)

    def one(k):
        image, half = reads(
            _render, paths[k], transfer=transfer, scale=scale, out=stack[k], channel=channel,
            view=view,
        )
        if np.isfinite(image.sum(dtype=np.float64)):  # one pass when every value is finite
            return 0, half
        return int((~np.isfinite(image)).any(axis=-1).sum()), half

    counts, stored = zip(*pool.map(one, range(len(paths))), strict=True)
    return stack, np.asarray(counts, dtype=np.int64), list(stored)


