"""A write that fails (a full disk, a file-size limit) is one line naming the store and the fix,
in the job's log; its partial output is removed and every result written before is kept."""

import builtins
import errno
import io
import os
import resource
import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from stereovar.errors import StereovarError
from stereovar.io.store import open_dataset, write_dataset, write_file
from stereovar.jobs.variance import variance_job

from .test_analysis_jobs import renders

REPO = Path(__file__).resolve().parents[1]


class _Disk:
    """Bytes still free on the simulated disk."""

    def __init__(self, free: int) -> None:
        self.free = int(free)


class _FileOnDisk:
    """A file opened for writing on a :class:`_Disk`: writes past its free space write what
    fits, then raise ``ENOSPC`` as a full file system does."""

    def __init__(self, handle, disk: _Disk) -> None:
        self._handle = handle
        self._disk = disk

    def write(self, data):
        size = len(data) if isinstance(data, str) else memoryview(data).nbytes
        if size > self._disk.free:
            fits = self._disk.free
            self._disk.free = 0
            if fits:
                part = data[:fits] if isinstance(data, str) else memoryview(data).cast("B")[:fits]
                self._handle.write(part)
                self._handle.flush()
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self._disk.free -= size
        return self._handle.write(data)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return self._handle.__exit__(*exc)

    def __getattr__(self, name):
        return getattr(self._handle, name)


@contextmanager
def small_disk(root, free: int):
    """Every file opened for writing under ``root`` shares ``free`` bytes, as if ``root`` were
    a file system with that much space left (``open``, ``io.open`` and so ``Path.open``)."""
    root = os.path.abspath(root)
    disk = _Disk(free)
    real_open = io.open

    def limited_open(file, mode="r", *args, **kwargs):
        handle = real_open(file, mode, *args, **kwargs)
        writing = any(c in mode for c in "wax+")
        if writing and isinstance(file, (str, bytes, os.PathLike)):
            name = os.path.abspath(os.fsdecode(file))
            if os.path.commonpath([name, root]) == root:
                return _FileOnDisk(handle, disk)
        return handle

    builtins.open = io.open = limited_open
    try:
        yield disk
    finally:
        builtins.open = io.open = real_open


def dataset(value: float) -> xr.Dataset:
    rng = np.random.default_rng(int(value))
    return xr.Dataset(
        {"radiance": (("seed", "y", "x"), value + rng.random((4, 32, 64), dtype=np.float32))},
        attrs={"what": f"value {value}"},
    )


def leftovers(folder: Path) -> list[str]:
    """Temporary siblings a write left behind."""
    return sorted(p.name for p in folder.iterdir() if ".tmp-" in p.name)


def assert_one_line_naming(message: str, path: Path, fix: str) -> None:
    assert "\n" not in message, message
    assert str(path) in message and fix in message, message
    assert "rerun the same command" in message and "nothing already computed is lost" in message


def test_a_full_disk_while_writing_a_store_names_the_store_and_keeps_the_old_one(tmp_path):
    store = tmp_path / "results" / "var.zarr"
    write_dataset(dataset(1.0), store)
    before = open_dataset(store)["radiance"].values.copy()
    with small_disk(tmp_path, free=20_000) as disk, pytest.raises(StereovarError) as err:
        write_dataset(dataset(2.0), store, chunk_dims={"seed": 1})
    assert disk.free == 0  # it failed mid-write, after part of the store was written
    assert_one_line_naming(str(err.value), store, f"free space at {store.parent}")
    assert "No space left on device" in str(err.value)
    assert leftovers(store.parent) == []
    np.testing.assert_array_equal(open_dataset(store)["radiance"].values, before)
    # once there is space the same call writes it
    write_dataset(dataset(2.0), store, chunk_dims={"seed": 1})
    np.testing.assert_array_equal(
        open_dataset(store)["radiance"].values, dataset(2.0)["radiance"].values
    )


def test_a_failed_rename_onto_a_store_puts_the_old_store_back(tmp_path, monkeypatch):
    store = tmp_path / "var.zarr"
    write_dataset(dataset(1.0), store)
    before = open_dataset(store)["radiance"].values.copy()
    real_rename = os.rename
    calls = []

    def rename(src, dst):
        if Path(dst) == store and not calls:  # the new store's move into place fails
            calls.append(src)
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(src), str(dst))
        return real_rename(src, dst)

    monkeypatch.setattr(os, "rename", rename)
    with pytest.raises(StereovarError) as err:
        write_dataset(dataset(2.0), store)
    monkeypatch.undo()
    assert calls and str(store) in str(err.value)
    np.testing.assert_array_equal(open_dataset(store)["radiance"].values, before)
    assert leftovers(tmp_path) == []


def test_a_full_disk_while_writing_a_file_names_the_file(tmp_path):
    out = tmp_path / "tables" / "scenes.csv"
    write_file(out, lambda tmp: Path(tmp).write_text("old\n"))
    with small_disk(tmp_path, free=100), pytest.raises(StereovarError) as err:
        write_file(out, lambda tmp: Path(tmp).write_text("new row\n" * 1000))
    assert_one_line_naming(str(err.value), out, f"free space at {out.parent}")
    assert leftovers(out.parent) == [] and out.read_text() == "old\n"


def test_an_error_reading_something_else_is_not_called_a_write_failure(tmp_path):
    def reads_a_missing_input(tmp):
        Path(tmp).write_text("partial")
        (tmp_path / "missing.csv").read_text()

    with pytest.raises(FileNotFoundError):
        write_file(tmp_path / "out.csv", reads_a_missing_input)
    assert leftovers(tmp_path) == [] and not (tmp_path / "out.csv").exists()


def job_code(paths, out, log) -> str:
    return (
        "from stereovar.jobs.common import run_job\n"
        "from stereovar.jobs.variance import variance_job\n"
        f"run_job({str(log)!r}, variance_job, left={[str(p) for p in paths['left']]!r}, "
        f"right={[str(p) for p in paths['right']]!r}, out={str(out)!r})\n"
    )


def assert_failed_with_one_logged_line(proc, log: Path, out: Path, fix: str) -> str:
    assert proc.returncode == 1, proc.stderr
    assert "Traceback" not in proc.stderr, proc.stderr
    errors = [ln for ln in proc.stderr.splitlines() if "error:" in ln]
    assert len(errors) == 1, proc.stderr
    logged = [ln for ln in log.read_text().splitlines() if "error:" in ln]
    assert logged == errors, log.read_text()
    message = errors[0].split("error: ", 1)[1]
    assert_one_line_naming(message, out, fix)
    assert not out.exists() and leftovers(out.parent) == []
    return message


def test_a_job_on_a_full_disk_logs_one_line_and_the_same_command_resumes(tmp_path):
    """The job runs in its own process, as under Snakemake, writing through the real write path
    onto a disk with too little space left."""
    paths = renders(tmp_path, 4)
    results = tmp_path / "results"
    results.mkdir()
    out, log = results / "var.zarr", tmp_path / "logs" / "variance.log"
    code = job_code(paths, out, log)
    full = (
        "from tests.test_write_faults import small_disk\n"
        f"with small_disk({str(results)!r}, free=4000):\n"
        + "".join(f"    {line}\n" for line in code.splitlines())
    )
    proc = subprocess.run([sys.executable, "-c", full], capture_output=True, text=True, cwd=REPO)
    message = assert_failed_with_one_logged_line(proc, log, out, f"free space at {results}")
    assert "No space left on device" in message
    # space freed: the same command completes, with the result of a run that never failed
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO)
    assert proc.returncode == 0, proc.stderr
    variance_job(paths["left"], paths["right"], tmp_path / "clean.zarr")
    clean, resumed = open_dataset(tmp_path / "clean.zarr"), open_dataset(out)
    assert sorted(resumed.data_vars) == sorted(clean.data_vars)
    for name in clean.data_vars:
        np.testing.assert_array_equal(resumed[name].values, clean[name].values)


def test_a_job_past_the_file_size_limit_logs_one_line(tmp_path):
    """A real failure of the kernel's write (``ulimit -f``: EFBIG), nothing simulated."""
    paths = renders(tmp_path, 4)
    out, log = tmp_path / "results" / "var.zarr", tmp_path / "logs" / "variance.log"
    limit = 4096  # below one chunk of the variance store, above every line of the log

    def limited():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    proc = subprocess.run(
        [sys.executable, "-c", job_code(paths, out, log)],
        capture_output=True,
        text=True,
        cwd=REPO,
        preexec_fn=limited,
    )
    message = assert_failed_with_one_logged_line(proc, log, out, "ulimit -f")
    assert "File too large" in message
