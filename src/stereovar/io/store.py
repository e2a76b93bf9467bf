"""Atomic writes of results: a finished path is either absent or complete.

Every artefact is written to a hidden temporary sibling first and renamed into place, so a
job killed mid-write leaves nothing that looks complete, and an existing result is replaced
only by a complete new one. A store that cannot be read gets one line with the command that
rebuilds it (:func:`store_error`, :func:`rebuild_command`).
"""

from __future__ import annotations

import errno
import os
import re
import shutil
import uuid
from collections.abc import Callable
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import StoreError
from ..processes import process_exists

ZARR_FORMAT = 2
"""Zarr format of stored datasets (v2 stores with consolidated metadata, readable by
zarr-python 2 and 3 alike)."""


_WRITE_FAILURES = {
    errno.ENOSPC: "free space at {where}",
    errno.EDQUOT: "free space at {where} (or raise your disk quota there)",
    errno.EFBIG: (
        "the file is larger than this process (ulimit -f) or the file system at {where} "
        "allows; raise the limit or write to another file system"
    ),
    errno.EROFS: "make {where} writable (its file system is mounted read-only)",
}
"""Errors only a write gives, with the fix of each (``{where}``: the target's folder)."""


def _one_line(text) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= 200 else text[:197] + "..."


RERUN_ARGS_ENV = "STEREOVAR_SNAKEMAKE_ARGS"
"""Environment variable holding the ``--configfile`` and ``--config`` options of the
Snakemake run a job belongs to (set by ``workflow/rules/inputs/run.smk``)."""


def set_rerun_arguments(args: str) -> None:
    """Record the ``--configfile`` and ``--config`` options of this Snakemake run for the
    jobs it starts (they inherit the environment), so :func:`rebuild_command` repeats them."""
    os.environ[RERUN_ARGS_ENV] = str(args)


def rebuild_command(path) -> str:
    """The command that rebuilds the workflow output at ``path`` and nothing else.

    ``stereovar run -j1 <this run's --configfile options> <path> -- --force <its --config
    options>``: ``stereovar run`` runs the workflow of the installed stereovar (a checkout's
    or a wheel's, where a bare ``snakemake`` finds no Snakefile) in the current directory,
    and ``--force`` reruns the one job that writes ``path`` (whether or not the damaged copy
    is still there) with the same config, so the rebuilt store matches the others. Outside
    a workflow run the config options are unknown, and the command says to add them.
    """
    import shlex

    args = os.environ.get(RERUN_ARGS_ENV)
    if args is None:
        files, rest = "--configfile <the config of the run that made it>", ""
    else:
        words = shlex.split(args)
        pairs = [k for k, word in enumerate(words[:-1]) if word == "--configfile"]
        files = shlex.join([w for k in pairs for w in words[k : k + 2]])
        rest = shlex.join([w for k, w in enumerate(words) if k not in pairs and k - 1 not in pairs])
    parts = ("stereovar run -j1", files, shlex.quote(str(path)), "-- --force", rest)
    return " ".join(p for p in parts if p)


def store_error(path, detail, *, what: str = "render store") -> StoreError:
    """The one-line error for a damaged or incomplete store at ``path``, with the command
    that rebuilds it (:func:`rebuild_command`)."""
    return StoreError(
        f"{what} {path} is damaged or incomplete ({_one_line(detail)}); "
        f"rebuild it with `{rebuild_command(path)}`"
    )


def read_errors() -> tuple[type[BaseException], ...]:
    """Exceptions that mean a store could not be read (zarr's own base class when present)."""
    import zarr.errors

    base = getattr(zarr.errors, "BaseZarrError", None)
    return (OSError, KeyError, ValueError, TypeError, RuntimeError, IndexError) + (
        (base,) if base is not None else ()
    )


def write_error(err: OSError, path, tmp=None):
    """The one-line error of ``err`` raised while writing ``path`` (through ``tmp``).

    Parameters
    ----------
    err : OSError
        What the write raised.
    path : path-like
        The result being written.
    tmp : path-like, optional
        The temporary path it was written to (:func:`atomic_path`).

    Returns
    -------
    stereovar.errors.WriteError or None
        ``cannot write <path>: <reason>; <fix>, then rerun the same command (nothing already
        computed is lost)``; None when ``err`` is not a failure to write there (a file it
        names lies elsewhere, e.g. an input read while writing), so the caller raises it
        unchanged.
    """
    from ..errors import WriteError

    path = Path(os.path.abspath(path))
    own = [path] + ([Path(os.path.abspath(tmp))] if tmp is not None else [])
    named = [
        Path(os.path.abspath(os.fsdecode(name)))
        for name in (err.filename, err.filename2)
        if isinstance(name, (str, bytes, os.PathLike))
    ]
    ours = any(n in own or any(o in n.parents for o in own) or n in path.parents for n in named)
    if err.errno not in _WRITE_FAILURES and not ours:
        return None
    where = next((d for d in path.parents if d.exists()), path.parent)
    if err.errno in _WRITE_FAILURES:
        fix = _WRITE_FAILURES[err.errno].format(where=where)
    elif err.errno in (errno.EACCES, errno.EPERM):
        fix = f"make {where} writable"
    else:
        fix = f"check {where} and the disk it is on"
    code = errno.errorcode.get(err.errno, "") if err.errno is not None else ""
    reason = (err.strerror or str(err)) + (f" ({code})" if code else "")
    return WriteError(
        f"cannot write {path}: {reason}; {fix}, then rerun the same command "
        "(nothing already computed is lost)"
    )


def _temporary_sibling(path: Path) -> Path:
    return path.with_name(f".{path.name}.tmp-{os.getpid()}-{uuid.uuid4().hex[:8]}")


_TEMPORARY = re.compile(r"\.(?P<name>.+)\.tmp-(?P<pid>[0-9]+)-[0-9a-f]{8}")
"""Names :func:`_temporary_sibling` gives: ``.{name}.tmp-{pid}-{8 hex digits}``."""


def stale_temporaries(folders, *, names=None) -> list[Path]:
    """Temporaries of :func:`atomic_path` in ``folders`` whose writing process is gone.

    A process killed while it wrote (SIGKILL, a power cut) leaves its hidden temporary
    sibling, ``.{name}.tmp-{pid}-{hex}``, behind; one whose ``pid`` is not a running process
    on this machine is stale. A live process's temporary is never listed.

    Parameters
    ----------
    folders : iterable of path-like
        Folders to look in (not recursively); missing ones are skipped.
    names : iterable of str, keyword-only, optional
        Only temporaries of results with these names (default: of any).

    Returns
    -------
    list of pathlib.Path
        Sorted.
    """
    names = None if names is None else set(names)
    stale = []
    for folder in folders:
        try:
            entries = list(os.scandir(folder))
        except (FileNotFoundError, NotADirectoryError):
            continue
        for entry in entries:
            m = _TEMPORARY.fullmatch(entry.name)
            if m is None or (names is not None and m["name"] not in names):
                continue
            if not process_exists(int(m["pid"])):
                stale.append(Path(entry.path))
    return sorted(stale)


def remove_stale_temporaries(folders, *, names=None) -> list[Path]:
    """Remove the :func:`stale_temporaries` of ``folders`` (and ``names``); returns them."""
    removed = []
    for path in stale_temporaries(folders, names=names):
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)
        if not os.path.lexists(path):
            removed.append(path)
    return removed


def _replace(tmp: Path, path: Path) -> None:
    """Move ``tmp`` onto ``path``; a directory already at ``path`` is removed only afterwards."""
    if path.is_dir() and not path.is_symlink():
        old = _temporary_sibling(path)
        os.rename(path, old)
        try:
            os.rename(tmp, path)
        except OSError:
            os.rename(old, path)  # the previous result stays where it was
            raise
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(tmp, path)


@contextmanager
def atomic_path(path):
    """Yield a temporary path to write to; rename it onto ``path`` if the block succeeds.

    On an exception the temporary file or directory is removed and ``path`` is untouched. A
    failure to write there (a full disk, a read-only folder; :func:`write_error`) is raised as
    a one-line :class:`~stereovar.errors.WriteError` naming ``path`` and the fix.
    """
    path = Path(path)
    tmp = _temporary_sibling(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        yield tmp
        _replace(tmp, path)
    except OSError as err:
        error = write_error(err, path, tmp)
        if error is None:
            raise
        raise error from err
    finally:
        if tmp.is_dir():
            shutil.rmtree(tmp, ignore_errors=True)
        elif tmp.exists():
            tmp.unlink()


CHUNK_BYTES = 32 * 2**20
"""Target chunk size: arrays are chunked along their first dimension only, in blocks of at
most this many bytes, so a whole image is one or a few chunks (cheap to read and stream)."""


def _chunks(variable, fixed: dict) -> tuple[int, ...]:
    """Chunks of ``variable``: ``fixed`` sizes for the dims it names; the first other dim in
    blocks of at most :data:`CHUNK_BYTES`; every remaining dim whole."""
    sizes = [min(int(fixed[d]), n) if d in fixed else n for d, n in variable.sizes.items()]
    free = [k for k, d in enumerate(variable.dims) if d not in fixed]
    if free:
        k = free[0]
        rest = int(np.prod([sizes[j] for j in range(len(sizes)) if j != k], dtype=np.int64))
        row_bytes = max(1, variable.dtype.itemsize * rest)
        sizes[k] = max(1, min(sizes[k], CHUNK_BYTES // row_bytes))
    return tuple(max(1, s) for s in sizes)


def write_dataset(ds: xr.Dataset | xr.DataArray, path, *, chunk_dims: dict | None = None) -> Path:
    """Write an xarray object to a Zarr store at ``path`` atomically.

    Every variable is chunked along its first dimension only (:data:`CHUNK_BYTES`), or with
    ``chunk_dims`` sizes for the dims named there (e.g. ``{"seed": 1}``: one render a chunk)
    and byte-sized blocks along the next one.
    """
    if isinstance(ds, xr.DataArray):
        ds = ds.to_dataset(name=ds.name or "data", promote_attrs=False)
    with atomic_path(path) as tmp:
        write_zarr(ds, tmp, chunk_dims=chunk_dims)
    return Path(path)


def write_zarr(ds: xr.Dataset, path, *, chunk_dims: dict | None = None) -> None:
    """Write a dataset to a Zarr store at ``path`` as :func:`write_dataset` does, but in
    place: ``path`` is one the caller owns until it is complete (a temporary path of
    :func:`atomic_path`)."""
    fixed = dict(chunk_dims or {})
    encoding = {name: {"chunks": _chunks(v, fixed)} for name, v in ds.data_vars.items() if v.ndim}
    # Every chunk is written, even one that holds only the fill value, so a missing chunk
    # file always means damage (what the completeness checks of the readers count).
    ds.to_zarr(
        path,
        mode="w",
        zarr_format=ZARR_FORMAT,
        consolidated=True,
        encoding=encoding,
        write_empty_chunks=True,
    )


def open_dataset(path) -> xr.Dataset:
    """Open a stored Zarr dataset lazily (``xarray.open_zarr``, numpy-backed: no dask graph;
    use ``xr.open_mfdataset`` or ``.chunk()`` for dask)."""
    return xr.open_zarr(path, consolidated=True, zarr_format=ZARR_FORMAT, chunks=None)


def load_store(path, what: str, variables=None) -> xr.Dataset:
    """Open a stored dataset and read it (or ``variables`` of it) into memory, checked.

    Parameters
    ----------
    path : path-like
        A workflow output (a ground-truth, variance or warped store).
    what : str
        What it is, for the message (``"variance store"``).
    variables : list of str, optional
        Read only these (attributes are kept).

    Raises
    ------
    StoreError
        The store is missing, lacks a variable or cannot be read (a damaged or missing
        chunk): one line with the command that rebuilds it
        (:func:`store_error`).
    """
    if not Path(path).exists():
        raise store_error(path, "it does not exist", what=what)
    try:
        ds = open_dataset(path)
        if variables is not None:
            ds = ds[list(variables)]
        return ds.load()
    except read_errors() as err:
        raise store_error(path, f"{type(err).__name__}: {err}", what=what) from None


def write_file(path, writer: Callable[[Path], None]) -> Path:
    """Write a file atomically: ``writer(tmp_path)`` writes, then the file is renamed."""
    with atomic_path(path) as tmp:
        writer(tmp)
    return Path(path)
