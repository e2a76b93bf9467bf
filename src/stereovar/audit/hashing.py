"""Reading an audit's files safely and cheaply: every file hashed (SHA-256) through the
descriptor it is decoded from (:func:`read_verified`, :class:`Reads`), and the fingerprint by
which Snakemake decides that a frame is imported again without hashing it
(:func:`frame_fingerprint`); whether a frame's files still hold the bytes its last import
recorded (:func:`unchanged_frame`).

Whether a file changed is decided on its content (SHA-256), never on its size and time
stamps alone: ``cp -p``, ``rsync -a`` and ``tar x`` keep both.
"""

from __future__ import annotations

import hashlib
import json
import os
import stat
import threading
import time
from pathlib import Path

from ..errors import AuditError, ImageError
from ..io.files import missing_error, not_regular_error
from .layout import Frame
from .records import load_record
from .settings import settings_digest

RECENT_NS = 2_000_000_000
"""A file last modified less than this many nanoseconds before it is opened is hashed again
after it is decoded (:func:`read_verified`): file time stamps advance in steps of a few
milliseconds, so a rewrite that soon after the previous one can leave them as they were."""


def sha256(path) -> str:
    """SHA-256 of a file's bytes."""
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()



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

    The job records the tokens it was given (:func:`~stereovar.audit.importer.import_frame`
    ``fingerprint``), so the fingerprint of a frame just imported is the one Snakemake
    stored.

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



class Reads:
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



def unchanged_frame(frame: Frame, previous: dict, stores: dict, pool) -> bool:
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


