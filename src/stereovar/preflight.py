"""Checks the workflow runs before any job starts, so a bad input costs no finished result.

Snakemake deletes a job's outputs before it runs the job, so an input problem found by the
job itself (a typo in a spec, a variant this machine lacks) would cost every output the job
replaces. The workflow therefore checks up front (``workflow/rules/inputs/scenes.smk``,
``workflow/rules/inputs/run.smk``):

* every listed scene spec, including the XML file it points at and every file that reads
  (:func:`check_scene_specs`), when the workflow is parsed;
* the back end a render would use on this machine, and whether the renders a run would pool
  into one table came from one back end (:func:`check_backends`), in ``onstart`` for local
  runs, where the variant ``auto`` resolves to is this machine's;
* a lock left by a run that was killed on this machine (:func:`stale_lock`), removed when
  the workflow is parsed so the same command resumes; the run that holds the lock marks
  itself in ``onstart`` (:func:`mark_run`);
* that the folders the run writes (:data:`WRITTEN_FOLDERS`) can be written
  (:func:`check_writable`), when the workflow is parsed: Snakemake would otherwise stop with
  a ``ProtectedOutputException`` naming no fix, or fail inside the first job.

``stereovar audit`` makes the workflow's checks of an audit before it starts Snakemake,
and two that only it makes: that the disk has room for Snakemake's lock and records
(:func:`check_free_space`), and, when Snakemake refuses the run because the folder is
locked, which run holds the lock (:func:`lock_message`), from the records it writes of each
Snakemake it starts (:func:`record_run`).
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import stat
import time
from collections.abc import Iterable, Mapping
from pathlib import Path

from .errors import BackendError, StereovarError
from .processes import process_exists

BACKEND_KEYS = ("renderer", "renderer_version", "variant")
"""Render attributes that must agree across the renders a table pools."""

STATE_DIR = ".snakemake"
"""Snakemake's folder in the folder a run works in: its locks, its records of each job, and
the run records of :data:`RUN_MARKER` and :data:`RUNS_DIR`."""

WRITTEN_FOLDERS = ("results", "logs", "benchmarks", STATE_DIR)
"""The folders, relative to the folder a run works in, that the run writes: what
:func:`check_writable` checks before anything is written."""

RUN_MARKER = "stereovar-run.json"
"""File in ``.snakemake/`` naming the host and process of the run that holds the lock
(:func:`mark_run`, once the run has taken it)."""

RUNS_DIR = "stereovar-runs"
"""Folder in ``.snakemake/`` with one record per Snakemake process that ``stereovar`` started
there (:func:`record_run`), written as it starts, before the process takes the lock."""

MIN_FREE_MB = 64
"""Free space (MB) a run needs before its first job: Snakemake's lock files, its records of
each job and the logs (:func:`check_free_space`)."""


def check_scene_specs(paths: Iterable) -> list[dict]:
    """Load every spec (:func:`stereovar.scenes.spec.load_scene_spec`), XML files included.

    Returns
    -------
    list of dict
        The validated specs, in order.

    Raises
    ------
    SceneError
        The first problem, in one line naming the file.
    """
    from .scenes.spec import load_scene_spec

    return [load_scene_spec(p) for p in paths]


def stored_backends(paths: Iterable) -> dict:
    """The :data:`BACKEND_KEYS` of each existing render store among ``paths``, read from its
    attributes alone (``.zattrs``; no pixel is read). Unreadable stores are skipped: reading
    them reports the damage."""
    out = {}
    for path in paths:
        attrs_file = Path(path) / ".zattrs"
        if not attrs_file.is_file():
            continue
        try:
            attrs = json.loads(attrs_file.read_text())
        except (OSError, ValueError):
            continue
        out[str(path)] = tuple(str(attrs.get(k, "")) for k in BACKEND_KEYS)
    return out


def _describe(backend: tuple) -> str:
    return " ".join(part for part in backend if part)


def check_backends(
    kept: Mapping, planned: Mapping | None = None, *, allow_mixed: bool = False
) -> None:
    """Stop a run whose renders would mix back ends within one table.

    Parameters
    ----------
    kept : Mapping
        Render store path to its back end (:func:`stored_backends`): the stores this run
        reads and does not render again.
    planned : Mapping, optional
        The back end this run's render jobs use (:meth:`Renderer.backend
        <stereovar.renderers.base.Renderer.backend>`), when it renders anything and the
        machine that renders is this one.
    allow_mixed : bool, keyword-only
        ``render.allow_mixed_backends``: accept the mix.

    Raises
    ------
    BackendError
        One line naming a store of each back end and the command that renders them again.
    """
    if allow_mixed:
        return
    groups: dict[tuple, str] = {}
    for path, backend in sorted(kept.items()):
        groups.setdefault(tuple(backend), path)
    if planned is not None:
        groups.setdefault(tuple(str(planned.get(k, "")) for k in BACKEND_KEYS), "")
    if len(groups) < 2:
        return
    parts = [
        f"{path} used {_describe(b)}" if path else f"this run would render with {_describe(b)}"
        for b, path in groups.items()
    ]
    raise BackendError(
        "renders pooled into one table would mix back ends: "
        + "; ".join(parts)
        + " (render them again with one back end: `snakemake ... --forcerun render`, "
        "or set render.allow_mixed_backends: true)"
    )


def process_start(pid: int) -> float | None:
    """When a process of this machine started (from ``/proc``).

    Parameters
    ----------
    pid : int
        The process id.

    Returns
    -------
    float or None
        Seconds since the epoch, to the clock tick; None where that cannot be told (no such
        process, no ``/proc``).
    """
    try:
        fields = Path(f"/proc/{int(pid)}/stat").read_text().rsplit(")", 1)[1].split()
        boot = next(
            float(line.split()[1])
            for line in Path("/proc/stat").read_text().splitlines()
            if line.startswith("btime ")
        )
        return boot + int(fields[19]) / os.sysconf("SC_CLK_TCK")  # field 22, starttime
    except (OSError, ValueError, IndexError, StopIteration):
        return None


def process_record(pid: int, command: str | None = None) -> dict:
    record = {"host": socket.gethostname(), "pid": int(pid), "started": process_start(pid)}
    return {**record, "command": command} if command else record


def _write_json(path: Path, data: dict) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}")
    tmp.write_text(json.dumps(data))
    os.replace(tmp, path)


def _alive(record: dict) -> bool | None:
    """Whether the process a record names still runs: None on another host (this machine
    cannot tell); a process of the same id started at another time is another process."""
    if record["host"] != socket.gethostname():
        return None
    if not process_exists(record["pid"]):
        return False
    started, now = record.get("started"), process_start(record["pid"])
    return started is None or now is None or abs(now - started) < 1.0


def run_records(state_dir) -> list[dict]:
    """The records of the runs of a folder: :data:`RUN_MARKER`, then each of
    :data:`RUNS_DIR`; unreadable ones are skipped.

    Parameters
    ----------
    state_dir : path-like
        Snakemake's folder (:data:`STATE_DIR`) of the folder the runs work in.

    Returns
    -------
    list of dict
        Each with ``host``, ``pid``, ``started`` (None if unknown), ``command`` (None if
        unknown), ``kind`` (``marker`` or ``started``) and ``path`` (the record's file).
    """
    state = Path(state_dir)
    runs = state / RUNS_DIR
    paths = [(state / RUN_MARKER, "marker")]
    if runs.is_dir():
        paths += [(p, "started") for p in sorted(runs.glob("*.json"))]
    records = []
    for path, kind in paths:
        try:
            data = json.loads(path.read_text())
            record = {"host": str(data["host"]), "pid": int(data["pid"])}
        except (OSError, ValueError, KeyError, TypeError):
            continue
        started = data.get("started")
        record["started"] = float(started) if isinstance(started, int | float) else None
        record["command"] = data.get("command") or None
        records.append({**record, "kind": kind, "path": path})
    return records


def _own(record: dict) -> bool:
    """Whether ``record`` is this very process's, written as it started (:data:`RUNS_DIR`):
    the workflow is parsed before Snakemake takes the lock, so it names no holder and no
    run that took the lock."""
    return (
        record["kind"] == "started"
        and record["host"] == socket.gethostname()
        and record["pid"] == os.getpid()
    )


def lock_holders(state_dir) -> list[dict]:
    """The recorded runs (:func:`run_records`) that may hold the locks of a folder.

    A record of this very process written as it started (:data:`RUNS_DIR`) names no
    holder: the process has not taken the lock yet.

    Parameters
    ----------
    state_dir : path-like
        Snakemake's folder (:data:`STATE_DIR`) of the locked folder.

    Returns
    -------
    list of dict
        One per process whose record says it still runs, or that ran on another host
        (this machine cannot tell), its records' fields merged (:func:`run_records`).
    """
    holders: dict = {}
    for record in run_records(state_dir):
        if _own(record):
            continue
        if _alive(record) is not False:
            key = (record["host"], record["pid"])
            holders[key] = {**holders.get(key, {}), **{k: v for k, v in record.items() if v}}
    return list(holders.values())


def _locked(state_dir) -> bool:
    locks = Path(state_dir) / "locks"
    return locks.is_dir() and any(locks.iterdir())


def _mtime(path: Path) -> float | None:
    try:
        return path.stat().st_mtime
    except OSError:
        return None


def _recorded(state_dir) -> list[dict]:
    """The records (:func:`run_records`) of the runs that may have taken the locks in
    ``state_dir``: all but this process's own (:func:`_own`), and a marker only when no
    lock file is newer than it. The marker is written after its run took the lock
    (:func:`mark_run`), so a newer lock was taken by a later run that has not reached
    ``onstart``: a plain ``snakemake`` run there is recorded nowhere until then."""
    locks = Path(state_dir) / "locks"
    times = [_mtime(p) for p in locks.iterdir()] if locks.is_dir() else []
    newest = max((t for t in times if t is not None), default=None)
    recorded = []
    for record in run_records(state_dir):
        if _own(record):
            continue
        if record["kind"] == "marker" and newest is not None:
            written = _mtime(record["path"])
            if written is None or written < newest:
                continue
        recorded.append(record)
    return recorded


def stale_lock(state_dir) -> bool:
    """Whether the locks in ``state_dir`` (``.snakemake``) belong to a run that is gone.

    True only when lock files exist, a run that may have taken them is recorded
    (:func:`_recorded`: the marker of the run that took the lock, unless a lock is newer
    than it, and the records ``stereovar`` wrote as it started runs, this process's own
    left out) and no recorded run may hold the lock (:func:`lock_holders`): every recorded
    process was of this host and no longer exists (a run killed by a signal or a lost
    session). A lock of a live run, of another host, or of no recorded run is not stale.
    """
    if not _locked(state_dir):
        return False
    return bool(_recorded(state_dir)) and not lock_holders(state_dir)


def clear_stale_lock(state_dir) -> bool:
    """Remove the lock files of a run that is gone (:func:`stale_lock`); True if removed."""
    if not stale_lock(state_dir):
        return False
    for path in (Path(state_dir) / "locks").iterdir():
        path.unlink(missing_ok=True)
    return True


def mark_run(state_dir) -> None:
    """Record this host and process, and when it started, as the holder of the run's lock
    (:data:`RUN_MARKER`), once the run has taken it; the records of processes of this host
    that are gone (:func:`record_run`) are removed then: until a run holds the lock, the
    record of a run killed before its ``onstart`` is what shows that run's lock is stale."""
    state = Path(state_dir)
    state.mkdir(parents=True, exist_ok=True)
    _write_json(state / RUN_MARKER, process_record(os.getpid()))
    for record in run_records(state):
        if record["kind"] == "started" and _alive(record) is False:
            record["path"].unlink(missing_ok=True)


def record_run(state_dir, pid: int, command: str) -> Path:
    """Record a Snakemake process started in a folder, before it takes its lock
    (:data:`RUNS_DIR`), so that a run it locks out can name it (:func:`lock_message`).

    The records of processes that are gone stay until a run has taken the lock
    (:func:`mark_run`).

    Parameters
    ----------
    state_dir : path-like
        Snakemake's folder (:data:`STATE_DIR`) of the folder the process works in.
    pid : int
        The Snakemake process.
    command : str
        The command that started it, as the user typed it (``stereovar audit a.yaml``).

    Returns
    -------
    Path
        The record, for :func:`forget_run` once the process has ended.
    """
    runs = Path(state_dir) / RUNS_DIR
    runs.mkdir(parents=True, exist_ok=True)
    path = runs / f"{socket.gethostname()}-{int(pid)}.json"
    _write_json(path, process_record(pid, command))
    return path


def forget_run(path) -> None:
    """Remove a record of :func:`record_run` once its process has ended.

    Parameters
    ----------
    path : path-like
        The record, as :func:`record_run` returned it; a record already gone is no error.
    """
    Path(path).unlink(missing_ok=True)


def describe_run(record: dict) -> str:
    where = "" if record["host"] == socket.gethostname() else f" on host {record['host']}"
    started = record.get("started")
    when = (
        f", started {time.strftime('%Y-%m-%d %H:%M:%S', time.localtime(started))}"
        if started
        else ""
    )
    command = f" ({record['command']})" if record.get("command") else ""
    return f"pid {record['pid']}{where}{when}{command}"


def _unconfirmed(record: dict) -> str | None:
    """When this machine cannot tell that a recorded holder still runs, the condition
    under which it does not: no run on its host any more (another host), or its pid no
    longer that run (this host, its start time unknown, so the pid may have been reused);
    None for a process of this host that started when the record says."""
    if record["host"] != socket.gethostname():
        return f"no run is going on host {record['host']} any more"
    if record.get("started") is None or process_start(record["pid"]) is None:
        return f"pid {record['pid']} is no longer a snakemake run in that folder"
    return None


def lock_message(state_dir, unlock: str) -> str:
    """What to say when Snakemake refuses a run because ``state_dir`` (``.snakemake``) is
    locked.

    Parameters
    ----------
    state_dir : path-like
        Snakemake's folder (``.snakemake``) of the locked run folder.
    unlock : str
        The command that removes the lock, shell-quoted (``stereovar run ... -- --unlock``).

    Returns
    -------
    str
        One line: who holds the lock (:func:`lock_holders`) and to wait for it, with
        ``unlock`` for when no run is going any more where this machine cannot tell (a
        holder on another host, or a pid of unknown start time, which may have been
        reused); that its holder has ended and the same command now goes on; or, when no
        run is recorded, ``unlock`` for when no Snakemake runs there any more.
        ``--unlock`` is never offered for a lock that a process of this host, started
        when its record says, may hold.
    """
    folder = Path(state_dir).absolute().parent
    holders = lock_holders(state_dir)
    if holders:
        runs = "; ".join(map(describe_run, holders))
        wait = (
            f"{folder} is locked by another run still going ({runs}); wait for it to "
            "finish, then run the same command again"
        )
        unsure = [_unconfirmed(h) for h in holders]
        if not all(unsure):
            return wait
        return (
            f"{wait}; if {' and '.join(dict.fromkeys(unsure))}, remove the lock with "
            f"`{unlock}` and run the same command again"
        )
    recorded = _recorded(state_dir)
    if recorded:
        ended = "; ".join(map(describe_run, recorded))
        return (
            f"{folder} was locked by a run that has ended ({ended}); run the same command "
            "again (the lock of a run that is gone is removed)"
        )
    return (
        f"{folder} is locked by a Snakemake run of which there is no record; wait for it to "
        "finish, or, if no snakemake process runs in that folder any more, remove the lock "
        f"with `{unlock}` and run the same command again"
    )


def check_free_space(folder, min_mb: int = MIN_FREE_MB) -> None:
    """Stop a run whose disk has less than ``min_mb`` MB free (:data:`MIN_FREE_MB`):
    Snakemake would fail to write its lock with a traceback before any job.

    Parameters
    ----------
    folder : path-like
        The folder the run works in; where it does not exist yet, its nearest existing
        parent's disk.
    min_mb : int, optional
        The free space a run needs, MB (10^6 bytes).

    Raises
    ------
    WriteError
        One line naming the folder, the space left and the fix.
    """
    from .errors import WriteError

    folder = Path(folder)
    probe = next((p for p in (folder, *folder.absolute().parents) if p.exists()), folder)
    free = shutil.disk_usage(probe).free
    if free < min_mb * 10**6:
        raise WriteError(
            f"the disk of {probe} is full ({free / 10**6:.1f} MB free, a run needs at least "
            f"{min_mb} MB for Snakemake's lock, records and logs); free space on it, then "
            "run the same command again"
        )


STORE_SUFFIX = ".zarr"
"""Directories written and replaced as one output: only the store itself is checked."""


def unwritable_paths(roots: Iterable) -> list[Path]:
    """The paths this process could not write or replace among ``roots`` and everything
    under them (top-down, inside a store only the store), in order.

    A root that does not exist stands for its nearest existing parent, in which the run
    would create it. Writability is :func:`os.access` with ``W_OK``, as Snakemake checks
    its outputs: it accounts for permissions, the user and read-only mounts, and writes
    nothing.
    """
    found: list[Path] = []
    for root in map(Path, roots):
        if not root.exists():
            parent = next(p for p in root.absolute().parents if p.exists())
            if not os.access(parent, os.W_OK):
                found.append(parent)
            continue
        if not os.access(root, os.W_OK):
            found.append(root)
        if not root.is_dir() or root.name.endswith(STORE_SUFFIX):
            continue
        for top, dirs, files in os.walk(root):
            for name in sorted(dirs) + sorted(files):
                path = Path(top) / name
                if not path.is_symlink() and not os.access(path, os.W_OK):
                    found.append(path)
            dirs[:] = sorted(d for d in dirs if not d.endswith(STORE_SUFFIX))
    return list(dict.fromkeys(found))


def _read_only_mount(path: Path) -> bool:
    try:
        return bool(os.statvfs(path).f_flag & os.ST_RDONLY)
    except OSError:
        return False


FS_IOC_GETFLAGS = 0x80086601
"""Linux ``ioctl`` that reads a file's attributes (``lsattr``)."""
FS_IMMUTABLE_FL, FS_APPEND_FL = 0x10, 0x20


def _locked_attribute(path: Path) -> str | None:
    """``immutable`` or ``append-only`` when ``path`` (a file or a folder) carries that
    attribute (``chattr +i``, ``chattr +a``: no one, root included, may replace it), else
    None (also where attributes cannot be read)."""
    try:
        import fcntl
        import struct

        if not stat.S_ISREG(os.stat(path).st_mode) and not path.is_dir():
            return None
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
        try:
            flags = struct.unpack_from("i", fcntl.ioctl(fd, FS_IOC_GETFLAGS, bytes(8)))[0]
        finally:
            os.close(fd)
    except (ImportError, OSError):
        return None
    if flags & FS_IMMUTABLE_FL:
        return "immutable"
    return "append-only" if flags & FS_APPEND_FL else None


def check_writable(roots: Iterable) -> None:
    """Stop a run that could not write its outputs (:func:`unwritable_paths`).

    Raises
    ------
    StereovarError
        One line naming the first such path, why (a read-only file system, or the
        permissions) and the fix, and how many more there are.
    """
    roots = [Path(r) for r in roots]
    found = unwritable_paths(roots)
    if not found:
        return
    first = found[0]
    # the fix covers the whole tree the first path is in
    top = next((r for r in roots if r.exists() and (r == first or r in first.parents)), first)
    more = f" ({len(found) - 1} more paths there are not writable either)" if found[1:] else ""
    attribute = _locked_attribute(first)
    if attribute:
        flag = "i" if attribute == "immutable" else "a"
        raise StereovarError(
            f"{first} is {attribute} (chattr +{flag}) and this run writes there{more}; "
            f"clear the attribute (chattr -{flag} {first}, as root) or run from a copy of the "
            "project"
        )
    if _read_only_mount(first):
        raise StereovarError(
            f"{first} is on a read-only file system and this run writes there{more}; "
            "remount it read-write, or run from a copy of the project on a writable disk"
        )
    raise StereovarError(
        f"{first} is not writable by this user and this run writes there{more}; make it "
        f"writable (chmod -R u+w {top}) or run as its owner"
    )
