"""Import an audit's files into the project's render and ground-truth store contracts.

:func:`import_audit` discovers the frames (:func:`stereovar.audit.layout.discover`), checks
every file's size from its header and re-imports only the frames whose files, or whose import
settings, changed since the last import (one record per frame,
``results/audit/{name}/import/{frame}.json``: :func:`import_record`). Whether a file changed
is decided on its content (SHA-256), never on its size and time stamps alone: ``cp -p``,
``rsync -a`` and ``tar x`` keep both. The workflow imports one frame per job
(:func:`import_frame`, rule ``audit_import``); Snakemake decides which frames to import again
(:func:`frame_fingerprint` is the rule's ``params``). A frame is imported by decoding all of
its files, checking them, settling the disparity sign photometrically
(:func:`stereovar.audit.sign.sign_check`) and only then writing its stores, each atomically:
a bad file stops the import with one line and leaves every store already imported as it was.

Each file is hashed and decoded while one open descriptor holds it, and checked afterwards
(:func:`read_verified`): a file replaced or rewritten meanwhile stops the import, so the
SHA-256 recorded with a store is always that of the bytes decoded into it.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import stat
import threading
import time
import warnings
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import AuditError, ImageError
from ..experiment import audit_source, batch_label, ground_truth_store, render_store
from ..io.channels import ROLES
from ..io.contracts import config_digest
from ..io.images import (
    image_format,
    image_size,
    integer_bits,
    missing_error,
    not_regular_error,
    read_field,
    read_image,
    read_labels,
    stored_as_half,
)
from ..io.renders import render_dataset
from ..io.store import (
    atomic_path,
    remove_stale_temporaries,
    stale_temporaries,
    write_file,
    write_zarr,
)
from ..layout import import_record
from ..rig import VIEWS
from .generators import (
    FOCAL_AGREEMENT,
    depth_size,
    read_camera,
    read_depth,
    stereo_geometry,
)
from .ground_truth import CONVENTIONS, disparity_from_depth, imported_ground_truth
from .layout import NAME, Discovery, Frame, discover
from .sign import HIGH_ERROR, sign_check

IMPORT_KEYS = (
    "views",
    "convention",
    "transfer",
    "scale",
    "disparity_scale",
    "focal_px",
    "baseline_m",
    "glass_ids",
    "spp",
    "sign_check",
    "channels",
)
"""``audit:`` settings that change what a frame imports to (a change re-imports it)."""

RELATIONS = {1: "x_R = x_L + d", -1: "x_R = x_L - d"}
"""The correspondence of each disparity sign :math:`s` (:data:`CONVENTIONS`), as the import's
lines write it."""

DEFAULT_DISPARITY_SCALE = 256.0
"""PNG disparity is value / 256 (KITTI); 0 is invalid."""

RECENT_NS = 2_000_000_000
"""A file last modified less than this many nanoseconds before it is opened is hashed again
after it is decoded (:func:`read_verified`): file time stamps advance in steps of a few
milliseconds, so a rewrite that soon after the previous one can leave them as they were."""


def audit_spp(settings: dict) -> int:
    """The SPP the audit's stores are labelled with: ``audit.spp``, or 0 (not given)."""
    return int(settings.get("spp") or 0)


def frame_stores(settings: dict, frame: str, n_seeds: int) -> dict:
    """View (and ``ground_truth``) to the store paths of one imported frame."""
    source = audit_source(settings["name"])
    batch = batch_label(range(n_seeds))
    stores = {
        view: render_store(source, frame, view, audit_spp(settings), batch) for view in VIEWS
    }
    stores["ground_truth"] = ground_truth_store(source, frame)
    return stores


def sha256(path) -> str:
    """SHA-256 of a file's bytes."""
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def _number(settings: dict, key: str, default):
    value = settings.get(key)
    if value is None:
        return default
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise AuditError(f"audit.{key} is {value!r}, not a number; give a number or leave it out")
    return float(value)


def import_settings(settings: dict) -> dict:
    """The ``audit:`` settings of :data:`IMPORT_KEYS` as the import applies them.

    Each one not given takes the value the import uses for it (the schema's default:
    ``convention: conventional``, ``scale: 1``, ``disparity_scale: 256``, ``glass_ids: []``,
    ``spp: 0``, ``sign_check: stop``, ``channels: {}``); numbers are floats (``scale: 1``
    and ``scale: 1.0`` are one import). The settings as written and the same settings with
    the schema's defaults filled in (the workflow's) so give one :func:`settings_digest`.

    Parameters
    ----------
    settings : dict
        The ``audit:`` config section.

    Returns
    -------
    dict
        :data:`IMPORT_KEYS` to their values.

    Raises
    ------
    AuditError
        A number that is not one, or an ``audit.channels`` entry that is not a role and a
        channel name (one line).
    """
    views = settings.get("views") or {}
    focal, baseline = _number(settings, "focal_px", None), _number(settings, "baseline_m", None)
    return {
        "views": {v: str(views.get(v, v)) for v in VIEWS},
        "convention": settings.get("convention") or "conventional",
        "transfer": settings.get("transfer") or None,
        "scale": _number(settings, "scale", 1.0),
        "disparity_scale": _number(settings, "disparity_scale", DEFAULT_DISPARITY_SCALE),
        "focal_px": focal or None,
        "baseline_m": baseline or None,
        "glass_ids": [int(i) for i in settings.get("glass_ids") or []],
        "spp": audit_spp(settings),
        "sign_check": settings.get("sign_check") or "stop",
        "channels": _channels(settings),
    }


def _channels(settings: dict) -> dict:
    """``audit.channels``, checked: role (:data:`~stereovar.io.channels.ROLES`) to the
    EXR channel (for ``render``, the layer) that holds it."""
    given = settings.get("channels") or {}
    if not isinstance(given, dict):
        raise AuditError(
            f"audit.channels is {given!r}; give a mapping of role to channel name, e.g. "
            "{depth: ViewLayer.Depth.Z}"
        )
    for role, name in given.items():
        if role not in ROLES:
            raise AuditError(
                f"audit.channels has the unknown role {role!r}; use {', '.join(ROLES)}"
            )
        if not isinstance(name, str) or not name:
            raise AuditError(
                f"audit.channels.{role} is {name!r}, not a channel name; give the EXR "
                "channel's name (e.g. ViewLayer.Depth.Z) or leave it out"
            )
    return {role: given[role] for role in ROLES if role in given}


def settings_digest(settings: dict) -> str:
    """SHA-256 of the :func:`import_settings` of ``settings`` (a change re-imports)."""
    return config_digest(import_settings(settings))


def _identity(st: os.stat_result) -> tuple:
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)


def _changed(path, before, fd, digest=None, f=None) -> str | None:
    """How the file ``fd`` opened at ``path`` differs from ``before`` (None: it does not)."""
    if _identity(os.fstat(fd)) != _identity(before):
        return "its size or time stamps changed"
    try:
        now = os.stat(path)
    except FileNotFoundError:
        return "it was removed"
    if _identity(now) != _identity(before):
        return "another file was moved to its path"
    if digest is not None and hashlib.file_digest(f, "sha256").hexdigest() != digest:
        return "its bytes changed"
    return None


def read_verified(path, decode=None) -> tuple[dict, object]:
    """Hash a file and decode it while one open descriptor holds it; check it did not change.

    The file is opened once; its bytes are hashed (SHA-256) through that descriptor and
    ``decode(path)`` reads them while it is held. Afterwards the descriptor's status and the
    path's must both equal those at the open (device, inode, size, modification and change
    times), and a file modified less than :data:`RECENT_NS` before the open is hashed again:
    the SHA-256 returned is that of the bytes decoded. (Decoding the hashed bytes from
    memory would need readers of bytes in :mod:`stereovar.io.images`; they take paths.)

    Parameters
    ----------
    path : path-like
    decode : callable, optional
        ``decode(path)`` reads the file (:func:`~stereovar.io.images.read_image`, ...);
        without it the file is only hashed.

    Returns
    -------
    record : dict
        ``{"sha256", "size", "mtime_ns"}`` of the file as hashed.
    value : object
        What ``decode`` returned (None without it).

    Raises
    ------
    ImageError
        The path cannot be opened or is not a regular file (a named pipe, a device).
    AuditError
        The file changed between its open and the end of decoding (one line).
    """
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)  # a named pipe must not block
    except FileNotFoundError:
        raise missing_error(path) from None
    except OSError as err:
        raise ImageError(
            f"{path}: cannot open it ({err.strerror}); make it readable or fix the audit path "
            "template"
        ) from None
    with os.fdopen(fd, "rb") as f:
        opened, before = time.time_ns(), os.fstat(fd)
        if not stat.S_ISREG(before.st_mode):
            raise not_regular_error(path, before.st_mode)
        digest = hashlib.file_digest(f, "sha256").hexdigest()
        value = None
        if decode is not None:
            try:
                value = decode(path)
            except Exception:
                if _changed(path, before, fd) is None:
                    raise  # a bad file, not a changed one
            recent = opened - max(before.st_mtime_ns, before.st_ctime_ns) < RECENT_NS
            f.seek(0)
            how = _changed(path, before, fd, digest if recent else None, f)
        else:
            how = _changed(path, before, fd)
    if how is not None:
        raise AuditError(
            f"{path} changed while it was imported ({how}); import again once it is written "
            "completely"
        )
    return _file_record(digest, before), value


def _file_record(digest: str, st: os.stat_result) -> dict:
    """A file's entry in an import record: its SHA-256 and the status it had when hashed."""
    return {
        "sha256": digest,
        "size": st.st_size,
        "mtime_ns": st.st_mtime_ns,
        "ctime_ns": st.st_ctime_ns,
        "ino": st.st_ino,
    }


FINGERPRINT_KEYS = ("size", "mtime_ns", "ctime_ns", "ino")
"""What :func:`frame_fingerprint` compares of a file's status with its import record."""


def frame_fingerprint(settings: dict, frame: Frame) -> str:
    """What decides that a frame is imported again, for Snakemake's ``params`` trigger.

    One token per file: the file's status (size, time stamps, inode) as its last import
    recorded it when the file still has that status or, when it has another, still holds
    the bytes recorded (it is hashed, only then); otherwise its status now. A file
    replaced by another of the same size and mtime (``cp -p``, ``tar x``: its ctime or
    inode changes) so changes the fingerprint, and a file only touched (``touch``, a
    checkout) does not; a frame never imported costs one ``stat`` per file, no hashing.
    Snakemake stores the fingerprint with the job's outputs and compares it at the next run.

    Parameters
    ----------
    settings : dict
        The ``audit:`` config section.
    frame : Frame
        The frame, from :func:`stereovar.audit.layout.discover`.

    The job records the tokens it was given (:func:`import_frame` ``fingerprint``), so the
    fingerprint of a frame just imported is the one Snakemake stored.

    Returns
    -------
    str
        JSON: the import-settings digest and the token of each file.
    """
    old = load_record(settings["name"], frame.name)
    recorded = old.get("files", {}) if old.get("settings") == settings_digest(settings) else {}
    tokens = {}
    for path in map(str, frame.files()):
        try:
            st = os.stat(path)
        except OSError:
            tokens[path] = None  # the import job names it
            continue
        now = [getattr(st, f"st_{k}") for k in FINGERPRINT_KEYS]
        before = recorded.get(path)
        if before is not None and all(k in before for k in FINGERPRINT_KEYS):
            then = [before[k] for k in FINGERPRINT_KEYS]
            if now == then or (now[0] == then[0] and sha256(path) == before["sha256"]):
                now = before.get("token", then)
        tokens[path] = now
    return json.dumps({"settings": settings_digest(settings), "files": tokens}, sort_keys=True)


class _Reads:
    """The files of one frame read so far (decoded or only hashed), each through
    :func:`read_verified`: path to its record. Safe to call from worker threads."""

    def __init__(self):
        self.records: dict = {}
        self._lock = threading.Lock()

    def __call__(self, decode, path, **options):
        """``decode(path, **options)`` (None: hash only) through :func:`read_verified`."""
        record, value = read_verified(
            path, None if decode is None else (lambda p: decode(p, **options))
        )
        with self._lock:
            self.records[str(path)] = record
        return value


WARNING_KINDS = {
    "sign_check": "sign check inconclusive",
    "sign_check_error": "sign check error high",
    "outside": "matches outside the other view",
    "transfer": "PNG transfer assumed",
    "quantisation": "variance quantised",
    "clipped": "clipped pixels",
    "glass_ids": "glass ids match nothing",
}
"""Kinds of import warnings (each a flagged row of the verdict page) and their labels."""

QUANTISED_WARNING = 0.001
"""Share of a view's valid pixels whose renders are all identical (8-bit PNG) from which the
import warns: quantisation floored their variance to 0."""

HALF_STEPS = 2.0
"""A pixel of half-float renders (:func:`_half_renders`) is quantised when its spread
across the seeds is below this many half-float steps (at its seed mean) in every channel:
its few distinct values distort its variance."""

OUTSIDE_WARNING = 0.5
"""Share of a frame's left pixels whose match falls outside the right image above which the
import warns: the disparity is too large for the image (a depth map, another unit)."""

CLIPPED_WARNING = 0.001
"""Share of a view's valid pixels at full scale in some render (PNG) above which the
import warns: a clipped pixel's variance is cut off."""


@dataclass
class FrameReport:
    """What importing one frame found (in a dry run: that it would be imported)."""

    name: str
    imported: bool
    nonfinite_pixels: dict = field(default_factory=dict)
    invalid_disparity: int = 0
    outside: int = 0
    valid: int = 0
    floored: dict = field(default_factory=dict)
    clipped: dict = field(default_factory=dict)
    """View to the share of its valid pixels at full scale in some render (PNG only)."""
    half: dict = field(default_factory=dict)
    """View to the share of its valid pixels whose spread across the seeds is below
    :data:`HALF_STEPS` half-float steps (renders in half precision only)."""
    sign: dict = field(default_factory=dict)
    n_seeds: int = 0

    def facts(self) -> dict:
        """What the import found, as JSON for the frame's :func:`import_record`."""
        return {
            "valid": self.valid,
            "invalid_disparity": self.invalid_disparity,
            "outside": self.outside,
            "nonfinite_pixels": self.nonfinite_pixels,
            "floored": self.floored,
            "clipped": self.clipped,
            "half": self.half,
            "sign": self.sign,
            "n_seeds": self.n_seeds,
        }


@dataclass
class ImportReport:
    """An audit's import: what was found, what was imported, and the warnings."""

    name: str
    discovery: Discovery
    frames: list
    warnings: list = field(default_factory=list)
    """The warnings' texts, in order."""
    flags: list = field(default_factory=list)
    """The warnings as ``{"kind", "frame", "text"}`` (``kind`` one of
    :data:`WARNING_KINDS`; ``frame`` None for the whole audit)."""
    seconds: dict = field(default_factory=dict)
    """Wall-clock seconds per phase (``hash`` of unchanged frames, ``ground truth``,
    ``decode`` (each including its files' hashes), ``sign check``, ``write``), summed over
    the frames."""
    dry_run: bool = False
    """Nothing was written: :attr:`frames` that are ``imported`` would be."""
    temporaries: list = field(default_factory=list)
    """Temporaries of killed imports removed (in a dry run: that would be)."""

    def warn(self, kind: str, text: str, frame: str | None = None) -> None:
        """Add a warning of a :data:`WARNING_KINDS` kind."""
        if kind not in WARNING_KINDS:
            raise ValueError(f"unknown warning kind {kind!r}; use one of {list(WARNING_KINDS)}")
        self.warnings.append(text)
        self.flags.append({"kind": kind, "frame": frame, "text": text})

    @contextmanager
    def timed(self, phase: str):
        """Add the time spent in the block to :attr:`seconds` ``[phase]``."""
        start = time.perf_counter()
        try:
            yield
        finally:
            elapsed = time.perf_counter() - start
            self.seconds[phase] = self.seconds.get(phase, 0.0) + elapsed

    def lines(self) -> list[str]:
        """Human-readable summary lines."""
        imported = [f.name for f in self.frames if f.imported]
        kept = len(self.frames) - len(imported)
        out = [
            f"audit {self.name}: {self.discovery.summary()}; "
            f"{'would import' if self.dry_run else 'imported'} "
            f"{len(imported)} frame{'s' * (len(imported) != 1)}"
            + (f" ({', '.join(imported)})" if imported else "")
            + f", {kept} unchanged"
            + (" (dry run: nothing written)" if self.dry_run else "")
        ]
        if self.temporaries:
            n = len(self.temporaries)
            pids = sorted({int(str(p.name).rsplit(".tmp-", 1)[1].split("-")[0])
                           for p in self.temporaries})
            shown = ", ".join(str(p) for p in self.temporaries[:3])
            out.append(
                f"  {'would remove' if self.dry_run else 'removed'} {n} "
                f"temporar{'y' if n == 1 else 'ies'} of killed imports "
                f"(process{'es' * (len(pids) > 1)} {', '.join(map(str, pids))}): {shown}"
                + (f" and {n - 3} more" if n > 3 else "")
            )
        for f in self.frames:
            if not f.imported or self.dry_run:
                continue
            bad = sum(f.nonfinite_pixels.values())
            out.append(
                f"  {f.name}: {f.valid} valid left pixels; {f.invalid_disparity} with NaN, "
                f"zero or negative disparity and {f.outside} whose match falls outside the "
                f"right image are invalid; {bad} render pixels with NaN/Inf (excluded)"
                + (
                    f"; sign check: median error {100 * f.sign['error']:.1f}% declared, "
                    f"{100 * f.sign['opposite_error']:.1f}% opposite"
                    if f.sign
                    else ""
                )
            )
        out += [f"  warning: {w}" for w in self.warnings]
        return out


def load_record(name: str, frame: str) -> dict:
    """The :func:`import_record` of a frame (empty when there is none or it is unreadable)."""
    path = Path(import_record(name, frame))
    try:
        return json.loads(path.read_text()) if path.is_file() else {}
    except (OSError, ValueError):
        return {}


def _unchanged(frame: Frame, previous: dict, stores: dict, pool) -> bool:
    """Whether the frame's stores exist and its files hold the bytes its last import
    recorded (same paths, sizes and SHA-256; time stamps are not trusted)."""
    old = previous.get("files", {})
    paths = [str(p) for p in frame.files()]
    if set(paths) != set(old) or not all(Path(s).is_dir() for s in stores.values()):
        return False
    try:
        if any(os.stat(p).st_size != old[p]["size"] for p in paths):
            return False
    except OSError:
        return False
    records = pool.map(lambda p: read_verified(p)[0], paths)
    return all(r["sha256"] == old[p]["sha256"] for p, r in zip(paths, records, strict=True))


def _store_folders(name: str) -> tuple[list, Path]:
    """The folders the import writes stores in, and the one of its records."""
    base = Path(import_record(name, "frame")).parent.parent
    folders = []
    for sub in ("renders", "ground_truth"):
        for folder, dirs, _ in os.walk(base / sub):
            folders.append(folder)
            dirs[:] = [d for d in dirs if not d.endswith(".zarr") and not d.startswith(".")]
    return folders, base


def _killed_imports(name: str, *, remove: bool) -> list:
    """Temporaries that killed imports of ``name`` left (removed with ``remove``)."""
    folders, base = _store_folders(name)
    find = remove_stale_temporaries if remove else stale_temporaries
    return find(folders) + find([Path(import_record(name, "frame")).parent])


def _check_sizes(frame: Frame) -> tuple[int, int]:
    """The frame's size from its files' headers; a file whose header gives another size than
    most of the frame's files is named, before any file is decoded. An Infinigen depth at
    twice the renders' size counts as the renders' size
    (:func:`~stereovar.audit.generators.depth_size`)."""
    sizes = {path: image_size(path) for path in frame.images()}
    render_size = sizes[next(iter(frame.renders[VIEWS[0]].values()))]
    for path in frame.ground_truth.get("depth", {}).values():
        sizes[path] = depth_size(path, render_size)
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


def _check_geometry(settings: dict, frame: Frame, optics: Optics, sign: int) -> None:
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


def _fields(settings: dict, frame: Frame, size, optics: Optics, reads: _Reads) -> tuple:
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


def _glass(settings: dict, frame: Frame, reads: _Reads):
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


def _integer_kind(frame: Frame, view: str) -> str:
    """``PNG`` or ``BlenderProc colors``: the kind of a view's integer renders, for the
    quantisation warning."""
    paths = frame.renders[view].values()
    return "PNG" if any(image_format(p) == "png" for p in paths) else "BlenderProc colors"


def _seed_mean(stack: np.ndarray, n_nonfinite) -> np.ndarray:
    """Mean over seeds, skipping NaN/Inf (a plain float64 mean when every value is finite)."""
    if not np.any(n_nonfinite):
        return stack.mean(axis=0, dtype=np.float64)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN pixels stay NaN
        return np.nanmean(np.where(np.isfinite(stack), stack, np.nan), axis=0)


def _check_distinct(stack: np.ndarray, frame: str, view: str, paths: list) -> None:
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


def _clipped_fraction(stack: np.ndarray, valid: np.ndarray, scale: float) -> float:
    """Fraction of ``valid`` pixels at a PNG's full scale (``scale`` after decoding) in some
    render and channel: their variance is cut off."""
    clipped = (stack >= np.float32(scale)).any(axis=(0, 3))
    return float((clipped & valid).sum() / max(int(valid.sum()), 1))


def _half_renders(stored: list, stack: np.ndarray) -> bool:
    """Whether a view's renders hold half-float (16-bit) values: as their files' headers
    say (``stored``: :func:`~stereovar.io.images.stored_as_half` of each file, an EXR
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


def _half_quantised_fraction(stack: np.ndarray, valid: np.ndarray, mean: np.ndarray) -> float:
    r"""Fraction of ``valid`` pixels whose spread across the N renders is below
    :data:`HALF_STEPS` half-float steps in every channel:
    :math:`s_c(x) < k\,\Delta_{16}(\bar I_c(x))` for every channel :math:`c`, with
    :math:`s_c` the sample standard deviation over the seeds, :math:`\bar I_c` the seed
    mean ``mean`` (:func:`_seed_mean`, float64 ``(H, W, 3)``), :math:`\Delta_{16}` the
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


def _floored_fraction(stack: np.ndarray, valid: np.ndarray) -> float:
    """Fraction of ``valid`` pixels whose N renders are identical in every channel (their
    estimated variance is 0: quantisation floored it)."""
    same = (stack == stack[:1]).all(axis=(0, 3))
    return float((same & valid).sum() / max(int(valid.sum()), 1))


def _render(path, *, channel=None, **options) -> tuple:
    """A render (:func:`~stereovar.io.images.read_image`) and whether its file stores it as
    half floats (:func:`~stereovar.io.images.stored_as_half`), in one verified read."""
    return read_image(path, channel=channel, **options), stored_as_half(path, channel=channel)


def _decode_view(
    paths: list, size: tuple, pool, transfer, scale, reads: _Reads, channel=None, view=0
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


def _import_frame(settings, frame: Frame, size, pool, report: ImportReport):
    """Import one frame: its ground truth, then its renders, the sign check and the stores.

    Every file is hashed as it is decoded (:func:`read_verified`); the SHA-256 recorded in
    the stores' provenance and returned are of the bytes decoded. Every store is written to
    a temporary path and renamed into place only once every file of the frame decoded and
    the sign check passed, so a failure leaves the frame's old stores as they were.

    Returns
    -------
    FrameReport, dict
        What the import found; each file's :func:`read_verified` record.
    """
    transfer, scale = settings["transfer"], settings["scale"]
    sign = CONVENTIONS[settings["convention"]]
    source = audit_source(settings["name"])
    fr = FrameReport(frame.name, True, n_seeds=frame.n_seeds)
    reads = _Reads()
    with report.timed("ground truth"):
        gt, gt_files = _frame_ground_truth(
            settings, frame, size, sign, source, fr, reads, report
        )
    datasets, means, view_files = {}, {}, {}
    for view in VIEWS:
        labels = list(frame.renders[view])
        paths = view_files[view] = [str(p) for p in frame.renders[view].values()]
        with report.timed("decode"):
            render_channel = settings["channels"].get("render")
            images, n_bad, stored = _decode_view(
                paths, size, pool, transfer, scale, reads,
                channel=render_channel, view=VIEWS.index(view),
            )
        fr.nonfinite_pixels[view] = int(n_bad.sum())
        _check_distinct(images, frame.name, view, paths)
        means[view] = _seed_mean(images, n_bad)
        valid = gt["valid"].sel(view=view).values
        bits = [integer_bits(p, channel=render_channel) for p in paths]
        if 8 in bits:
            fr.floored[view] = _floored_fraction(images, valid)
        if any(b is not None for b in bits):
            fr.clipped[view] = _clipped_fraction(images, valid, scale)
        elif _half_renders(stored, images):
            fr.half[view] = _half_quantised_fraction(images, valid, means[view])
        datasets[view] = render_dataset(
            images,
            view=view,
            seeds=list(range(len(paths))),
            sampler_seeds=[int(s) if s.isdigit() else k for k, s in enumerate(labels)],
            n_nonfinite=n_bad,
            attrs={
                "scene": frame.name,
                "renderer": source,
                "renderer_version": "",
                "variant": "imported",
                "spp": audit_spp(settings),
                "seed_policy": "unknown",
                "width": int(size[1]),
                "height": int(size[0]),
                "seed_labels": labels,
                "source_files": paths,
                "transfer": transfer or "",
            },
        )
    with report.timed("hash"):  # ground truth no statistic reads (a right-view mask)
        for path in frame.files():
            if str(path) not in reads.records:
                reads(None, path)
    files = {str(p): reads.records[str(p)]["sha256"] for p in frame.files()}
    digest = config_digest({"files": files, "settings": settings_digest(settings)})
    for view in VIEWS:
        datasets[view].attrs.update(
            scene_digest=digest, source_sha256=[files[p] for p in view_files[view]]
        )
    gt.attrs.update(scene_digest=digest, source_sha256=[files[p] for p in gt_files])
    with report.timed("sign check"):
        _check_sign(settings, frame, gt, means, sign, fr, report)
    datasets["ground_truth"] = gt
    stores = frame_stores(settings, frame.name, frame.n_seeds)
    with report.timed("write"), ExitStack() as staged:  # renamed into place together
        for key, ds in datasets.items():
            tmp = staged.enter_context(atomic_path(stores[key]))
            write_zarr(ds, tmp, chunk_dims={"seed": 1} if key in VIEWS else None)
    for view, fraction in fr.floored.items():
        if fraction < QUANTISED_WARNING:
            continue
        report.warn(
            "quantisation",
            f"frame {frame.name}, {view}: 8-bit {_integer_kind(frame, view)} quantisation "
            "floors the variance to 0 at "
            f"{100 * fraction:.1f}% of the valid pixels (all {frame.n_seeds} renders "
            "identical); export 16-bit PNG or EXR for an audit that can see small variance",
            frame.name,
        )
    for view, fraction in fr.half.items():
        if fraction < QUANTISED_WARNING:
            continue
        report.warn(
            "quantisation",
            f"frame {frame.name}, {view}: the renders hold half-float (16-bit) values, and at "
            f"{100 * fraction:.1f}% of the valid pixels their spread across the "
            f"{frame.n_seeds} renders is below {HALF_STEPS:g} half-float steps, so "
            "quantisation distorts the variance; export 32-bit float EXR (Blender: Color "
            "Depth Float (Full)) for an audit that can see small variance",
            frame.name,
        )
    for view, fraction in fr.clipped.items():
        if fraction > CLIPPED_WARNING:
            report.warn(
                "clipped",
                f"frame {frame.name}, {view}: {100 * fraction:.1f}% of the valid pixels are "
                "at the PNG's full scale in some render, where the variance is cut off; "
                "export EXR (or lower the exposure) so bright pixels keep their noise",
                frame.name,
            )
    return fr, {str(p): reads.records[str(p)] for p in frame.files()}


def _frame_ground_truth(
    settings, frame: Frame, size, sign, source, fr: FrameReport, reads: _Reads,
    report: ImportReport,
):
    """The frame's ground-truth dataset (its ``scene_digest`` and ``source_sha256`` are set
    once every file is read) and its files; fills the disparity counts of ``fr``."""
    optics = frame_optics(settings, frame, size, reads)
    _check_geometry(settings, frame, optics, sign)
    disparity, depth = _fields(settings, frame, size, optics, reads)
    glass, glass_source, unmatched = _glass(settings, frame, reads)
    if unmatched:
        report.warn("glass_ids", f"frame {frame.name}: {unmatched}", frame.name)
    gt_files = [str(p) for paths in frame.ground_truth.values() for p in paths.values()]
    gt_files = list(dict.fromkeys(gt_files + [str(p) for p in frame.cameras.values()]))
    gt, counts = imported_ground_truth(
        disparity[VIEWS[0]],
        sign=sign,
        disparity_right=disparity.get(VIEWS[1]),
        depth=depth,
        glass=glass,
        material_source=glass_source,
        attrs={
            "scene": frame.name,
            "renderer": source,
            "baseline_m": float(optics.baseline_m or 0.0),
            "focal_px": float(optics.focal_px or 0.0),
            "source_files": gt_files,
        },
    )
    if counts["valid"] == 0:
        path = frame.ground_truth.get("disparity", frame.ground_truth.get("depth"))[VIEWS[0]]
        raise AuditError(
            f"{path}: no valid disparity (NaN, zero or negative everywhere, or every match "
            "outside the right image); give positive disparity magnitudes in px"
        )
    fr.invalid_disparity, fr.outside, fr.valid = (
        counts["invalid_disparity"],
        counts["outside"],
        counts["valid"],
    )
    total = int(gt.sizes["y"] * gt.sizes["x"])
    if counts["outside"] > OUTSIDE_WARNING * total:
        report.warn(
            "outside",
            f"frame {frame.name}: {counts['outside']} of the {total} left pixels "
            f"({100 * counts['outside'] / total:.1f}%) have a disparity whose match falls "
            f"outside the right image ({gt.sizes['x']} px wide, {RELATIONS[sign]}): the "
            "disparity is too large for these images, as a depth map or a disparity in "
            "another unit or scale is; check audit.disparity (or audit.depth), its channel and "
            "audit.disparity_scale",
            frame.name,
        )
    return gt, gt_files


def _check_sign(settings, frame: Frame, gt, means, sign, fr: FrameReport, report) -> None:
    """The photometric sign check (:func:`stereovar.audit.sign.sign_check`) of one frame:
    one line naming the convention to set when the opposite one matches clearly better."""
    left_gt = gt.sel(view="left")
    compare = left_gt["valid"].values & ~left_gt["glass"].values & ~left_gt["occluded"].values
    check = sign_check(
        means["left"], means["right"], left_gt["disparity"].values, sign=sign, valid=compare
    )
    if check.opposite_wins:
        other = "conventional" if sign == 1 else "paper"
        raise AuditError(
            f"frame {frame.name}: the disparity follows the other convention: the right seed "
            f"mean warped into the left matches with a median error of "
            f"{100 * check.opposite_error:.1f}% under {RELATIONS[-sign]} but "
            f"{100 * check.error:.1f}% under the declared {RELATIONS[sign]}; set "
            f"audit.convention: {other}"
        )
    convention = settings.get("convention") or "conventional"
    errors = (
        f"median error {100 * check.error:.1f}% declared, "
        f"{100 * check.opposite_error:.1f}% opposite"
    )
    if not check.conclusive and settings.get("sign_check", "stop") != "warn":
        raise AuditError(
            f"frame {frame.name}: the sign check is inconclusive: {check.reason} ({errors}), "
            "so the disparity may be wrong (another convention, a wrong file or channel); "
            "check audit.disparity or audit.depth and audit.convention, or set "
            f"audit.sign_check: warn to go on with convention {convention} taken as given"
        )
    if not check.conclusive:
        report.warn(
            "sign_check",
            f"frame {frame.name}: the sign check is inconclusive: {check.reason} ({errors}); "
            f"audit.convention: {convention} is taken as given (audit.sign_check: warn)",
            frame.name,
        )
    if check.conclusive and check.high_error:
        report.warn(
            "sign_check_error",
            f"frame {frame.name}: the declared convention wins the sign check but matches "
            f"poorly ({errors}; above {100 * HIGH_ERROR:.0f}% the right seed mean warped "
            "into the left does not reproduce it): the disparity may not be this frame's (a "
            "depth map, another frame, file or channel, a wrong scale) or the seed means are "
            "very noisy; check audit.disparity or audit.depth and audit.channels",
            frame.name,
        )
    gt.attrs.update(check.attrs())
    fr.sign = {
        "error": check.error,
        "opposite_error": check.opposite_error,
        "conclusive": check.conclusive,
        "high_error": check.high_error,
        "reason": check.reason,
    }


PATH_KEYS = ("root", "renders", "disparity", "depth", "glass_mask", "segmentation")
"""``audit:`` settings that are paths (or path templates) of the audit's files."""

PATH_VARIABLE = re.compile(r"<[a-z][a-z0-9_]*>")
"""What Snakemake (9.x) reads as a path variable in an input or output path: ``<word>``,
replaced by its folder (``<results>``, ``<resources>``, ...) or an error when unknown."""


def check_paths(settings: dict) -> None:
    """Refuse an audit path that holds a Snakemake path variable (:data:`PATH_VARIABLE`).

    The audit's files are the inputs of its ``audit_import`` jobs: Snakemake stops on an
    unknown ``<b>`` in them (``UndefinedPathvarException``) and silently puts its own folder
    in place of a known one (``<results>``).

    Parameters
    ----------
    settings : dict
        The ``audit:`` config section: :data:`PATH_KEYS` and the ``views`` values, which
        become parts of the render and ground-truth paths.

    Raises
    ------
    AuditError
        One line naming the key, the path variable and the fix.

    Examples
    --------
    >>> check_paths({"renders": "data/{frame}/{view}/seed_{seed}.exr"})
    >>> check_paths({"renders": "data/<results>/{view}/{seed}.exr"})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    stereovar.errors.AuditError: audit.renders 'data/<results>/{view}/{seed}.exr' holds ...
    """
    views = settings.get("views") or {}
    given = [(key, settings.get(key)) for key in PATH_KEYS]
    given += [(f"views.{view}", views.get(view)) for view in VIEWS]
    for key, value in given:
        match = PATH_VARIABLE.search(str(value)) if value is not None else None
        if match:
            raise AuditError(
                f"audit.{key} {value!r} holds {match.group()}, which Snakemake reads as a "
                "path variable (an unknown one stops the workflow, a known one such as "
                "<results> is replaced by its folder); rename the folder or file so that "
                f"no <word> is in the path, and set audit.{key} to the new path"
            )


def check_settings(settings: dict) -> None:
    """The ``audit:`` settings that need no file: the name, the convention and the paths
    (:func:`check_paths`)."""
    check_paths(settings)
    name = str(settings.get("name") or "")
    if not NAME.fullmatch(name):
        raise AuditError(
            f"audit.name {name!r} may only contain letters, digits, _ and - (it names "
            "results/audit/<name>/); pick another name"
        )
    convention = settings.get("convention") or "conventional"
    if convention not in CONVENTIONS:
        raise AuditError(
            f"audit.convention {convention!r} is unknown; use "
            + " or ".join(f"{name} ({RELATIONS[s]})" for name, s in CONVENTIONS.items())
        )


def _png_transfer_warning(settings: dict, frames, report: ImportReport) -> None:
    """Warn once when integer renders (PNG, BlenderProc's integer ``colors``) are decoded
    as sRGB because ``audit.transfer`` is not set."""
    if settings["transfer"]:
        return
    renders = list(dict.fromkeys(p for f in frames for v in VIEWS for p in f.renders[v].values()))
    if any(image_format(p) == "png" for p in renders):
        report.warn(
            "transfer",
            "PNG renders without audit.transfer are decoded as sRGB; set audit.transfer: "
            "linear or srgb to say how they were written",
        )
    channel = settings["channels"].get("render")
    hdf5_bits = {
        integer_bits(p, channel=channel) for p in renders if image_format(p) == "hdf5"
    }
    if hdf5_bits - {None}:
        report.warn(
            "transfer",
            f"BlenderProc {'/'.join(f'{b}-bit' for b in sorted(hdf5_bits - {None}))} colors "
            "without audit.transfer are decoded as sRGB, which does not undo Blender's view "
            "transform (Filmic in BlenderProc's defaults) or its clipping at 1; render with "
            "bproc.renderer.set_output_format('OPEN_EXR', 32) for linear float colors, or "
            "set audit.transfer: linear or srgb to say how they were written",
        )


def _import_and_record(
    settings, frame: Frame, size, pool, report: ImportReport, tokens=None
) -> FrameReport:
    """Import one frame (:func:`_import_frame`), then write its :func:`import_record` (with
    each file's :func:`frame_fingerprint` token from ``tokens``)."""
    try:
        fr, records = _import_frame(settings, frame, size, pool, report)
    except MemoryError:
        raise AuditError(
            f"frame {frame.name}: its renders do not fit in memory; import fewer seeds per "
            "frame"
        ) from None
    stores = frame_stores(settings, frame.name, frame.n_seeds)
    for path, token in (tokens or {}).items():
        if path in records and token is not None:
            records[path] = {**records[path], "token": token}
    flags = [f for f in report.flags if f["frame"] in (None, frame.name)]
    _write_record(settings, frame.name, records, stores, {**fr.facts(), "warnings": flags})
    return fr


def import_audit(settings: dict, *, workers: int = 2, dry_run: bool = False) -> ImportReport:
    """Import an audit's files into the render and ground-truth store contracts.

    Every frame whose files or import settings changed since its :func:`import_record`
    (judged by SHA-256) is imported; the workflow imports one frame per job instead
    (:func:`import_frame`). For notebooks, benchmarks and tests.

    Parameters
    ----------
    settings : dict
        The ``audit:`` config section (see ``workflow/schemas/config.schema.yaml``), as
        written or with the schema's defaults filled in (one import either way).
    workers : int, keyword-only
        Threads that hash and decode files.
    dry_run : bool, keyword-only
        Only find what an import would do (which frames changed: their files are hashed),
        and write nothing.

    Returns
    -------
    ImportReport
        Frames found, imported (or that would be) and unchanged, temporaries of killed
        imports removed, and warnings (8-bit PNG floors, PNG transfer assumed, inconclusive
        sign checks).

    Raises
    ------
    AuditError, ImageError
        One line naming the file and the fix; stores already imported are left as they are.
    """
    check_settings(settings)
    settings = {**settings, **import_settings(settings)}
    found = discover(settings)
    name = settings["name"]
    report = ImportReport(name, found, [], dry_run=dry_run)
    report.temporaries = _killed_imports(name, remove=not dry_run)
    digest = settings_digest(settings)
    _png_transfer_warning(settings, found.frames, report)
    sizes = [_check_sizes(frame) for frame in found.frames]
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        for frame, size in zip(found.frames, sizes, strict=True):
            prev = load_record(name, frame.name)
            stores = frame_stores(settings, frame.name, frame.n_seeds)
            with report.timed("hash"):
                unchanged = prev.get("settings") == digest and _unchanged(
                    frame, prev, stores, pool
                )
            if unchanged:
                report.frames.append(FrameReport(frame.name, False))
            elif dry_run:
                report.frames.append(FrameReport(frame.name, True))
            else:
                report.frames.append(_import_and_record(settings, frame, size, pool, report))
    return report


def import_frame(
    settings: dict, frame: str, *, workers: int = 2, fingerprint: str | None = None
) -> ImportReport:
    """Import one frame of an audit, whatever its last import recorded: the job of the
    workflow's ``audit_import`` rule, which Snakemake runs when the frame's files (their
    time stamps, or :func:`frame_fingerprint`) or the import settings changed.

    The frame's files are found again (:func:`~stereovar.audit.layout.discover`), their
    sizes checked from their headers, then decoded and checked (:func:`_import_frame`:
    truncated files, the sign check, ...) before any store is written; the stores and the
    frame's :func:`import_record` are each written atomically.

    Parameters
    ----------
    settings : dict
        The ``audit:`` config section.
    frame : str
        The frame's name.
    workers : int, keyword-only
        Threads that hash and decode files.
    fingerprint : str, keyword-only, optional
        The frame's :func:`frame_fingerprint` when Snakemake planned the job: each file's
        token is recorded.

    Returns
    -------
    ImportReport
        With the one frame.

    Raises
    ------
    AuditError, ImageError
        One line naming the file and the fix; no store of the frame is written.
    """
    check_settings(settings)
    settings = {**settings, **import_settings(settings)}
    found = discover(settings)
    match = [f for f in found.frames if f.name == frame]
    if not match:
        raise AuditError(
            f"frame {frame}: no file of it matches audit.renders {settings['renders']!r} any "
            "more; run the workflow again (it finds the frames anew)"
        )
    report = ImportReport(settings["name"], found, [])
    names = {Path(p).name for p in frame_stores(settings, frame, match[0].n_seeds).values()}
    folders, _ = _store_folders(settings["name"])
    report.temporaries = remove_stale_temporaries(folders, names=names) + (
        remove_stale_temporaries(
            [Path(import_record(settings["name"], frame)).parent],
            names=[Path(import_record(settings["name"], frame)).name],
        )
    )
    _png_transfer_warning(settings, match, report)
    size = _check_sizes(match[0])
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        tokens = json.loads(fingerprint)["files"] if fingerprint else None
        report.frames.append(
            _import_and_record(settings, match[0], size, pool, report, tokens)
        )
    return report


def _write_record(settings: dict, frame: str, files: dict, stores: dict, found: dict) -> None:
    """Write a frame's :func:`import_record` atomically (not again when unchanged):
    ``found`` is what the import found (:meth:`FrameReport.facts` and its ``warnings``),
    which the verdict page shows."""
    record = {
        "audit": settings["name"],
        "frame": frame,
        "settings": settings_digest(settings),
        "files": files,
        "stores": stores,
        "found": found,
    }
    text = json.dumps(record, indent=1)
    path = Path(import_record(settings["name"], frame))
    try:
        if path.read_text() == text:
            return
    except (OSError, UnicodeDecodeError):
        pass
    write_file(path, lambda tmp: Path(tmp).write_text(text))
