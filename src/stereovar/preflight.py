"""Checks the workflow runs before any job starts, so a bad input costs no finished result.

Snakemake deletes a job's outputs before it runs the job, so an input problem found by the
job itself (a typo in a spec, a variant this machine lacks) would cost every output the job
replaces. The workflow therefore checks up front (``workflow/rules/common.smk``):

* every listed scene spec, including the XML file it points at and every file that reads
  (:func:`check_scene_specs`), when the workflow is parsed;
* the back end a render would use on this machine, and whether the renders a run would pool
  into one table came from one back end (:func:`check_backends`), in ``onstart`` for local
  runs, where the variant ``auto`` resolves to is this machine's;
* a lock left by a run that was killed on this machine (:func:`stale_lock`), so the same
  command resumes;
* that the directories the run writes (``results/``, ``logs/``, ...) can be written
  (:func:`check_writable`), when the workflow is parsed: Snakemake would otherwise stop with
  a ``ProtectedOutputException`` naming no fix, or fail inside the first job.
"""

from __future__ import annotations

import json
import os
import socket
from collections.abc import Iterable, Mapping
from pathlib import Path

from .errors import BackendError, StereovarError
from .processes import process_exists

BACKEND_KEYS = ("renderer", "renderer_version", "variant")
"""Render attributes that must agree across the renders a table pools."""

RUN_MARKER = "stereovar-run.json"
"""File in ``.snakemake/`` naming the host and process of the run that holds the lock."""


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


def stale_lock(state_dir) -> bool:
    """Whether the locks in ``state_dir`` (``.snakemake``) belong to a run that is gone.

    True only when lock files exist and :data:`RUN_MARKER` names this host and a process
    that no longer exists (a run killed by a signal or a lost session). A lock of a live
    run, of another host, or without a marker is not stale.
    """
    state = Path(state_dir)
    locks = state / "locks"
    if not locks.is_dir() or not any(locks.iterdir()):
        return False
    try:
        marker = json.loads((state / RUN_MARKER).read_text())
        host, pid = marker["host"], int(marker["pid"])
    except (OSError, ValueError, KeyError, TypeError):
        return False
    return host == socket.gethostname() and pid != os.getpid() and not process_exists(pid)


def clear_stale_lock(state_dir) -> bool:
    """Remove the lock files of a run that is gone (:func:`stale_lock`); True if removed."""
    if not stale_lock(state_dir):
        return False
    for path in (Path(state_dir) / "locks").iterdir():
        path.unlink(missing_ok=True)
    return True


def mark_run(state_dir) -> None:
    """Record this host and process as the holder of the run's lock (:data:`RUN_MARKER`)."""
    state = Path(state_dir)
    state.mkdir(parents=True, exist_ok=True)
    tmp = state / f".{RUN_MARKER}.{os.getpid()}"
    tmp.write_text(json.dumps({"host": socket.gethostname(), "pid": os.getpid()}))
    os.replace(tmp, state / RUN_MARKER)


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
    if _read_only_mount(first):
        raise StereovarError(
            f"{first} is on a read-only file system and this run writes there{more}; "
            "remount it read-write, or run from a copy of the project on a writable disk"
        )
    raise StereovarError(
        f"{first} is not writable by this user and this run writes there{more}; make it "
        f"writable (chmod -R u+w {top}) or run as its owner"
    )
