"""Start-up checks: back-end mixes and the locks of killed runs."""

import json
import os
import socket
import subprocess
import sys

import pytest

from stereovar.errors import BackendError
from stereovar.preflight import (
    RUN_MARKER,
    check_backends,
    clear_stale_lock,
    mark_run,
    stale_lock,
    stored_backends,
)

LLVM = ("mitsuba", "3.9.1", "llvm_ad_rgb")


def test_one_back_end_passes_and_a_second_one_names_a_store_of_each():
    kept = {"a.zarr": LLVM, "b.zarr": LLVM}
    check_backends(kept)
    check_backends(
        kept, {"renderer": "mitsuba", "renderer_version": "3.9.1", "variant": "llvm_ad_rgb"}
    )
    with pytest.raises(BackendError) as err:
        check_backends(
            kept, {"renderer": "mitsuba", "renderer_version": "3.9.1", "variant": "cuda_ad_rgb"}
        )
    assert "a.zarr used mitsuba 3.9.1 llvm_ad_rgb" in str(err.value)
    assert "this run would render with mitsuba 3.9.1 cuda_ad_rgb" in str(err.value)
    with pytest.raises(BackendError, match="b.zarr used mitsuba 3.10.0 llvm_ad_rgb"):
        check_backends({"a.zarr": LLVM, "b.zarr": ("mitsuba", "3.10.0", "llvm_ad_rgb")})
    check_backends({"a.zarr": LLVM, "b.zarr": ("mitsuba", "3.10.0", "x")}, allow_mixed=True)


def test_stored_back_ends_come_from_the_store_attributes(tmp_path):
    store = tmp_path / "s.zarr"
    store.mkdir()
    (store / ".zattrs").write_text(
        json.dumps(dict(zip(("renderer", "renderer_version", "variant"), LLVM, strict=True)))
    )
    (tmp_path / "broken.zarr").mkdir()
    (tmp_path / "broken.zarr" / ".zattrs").write_text("{")
    got = stored_backends([store, tmp_path / "broken.zarr", tmp_path / "missing.zarr"])
    assert got == {str(store): LLVM}


def test_only_the_lock_of_a_dead_run_on_this_host_is_stale(tmp_path):
    state = tmp_path / ".snakemake"
    (state / "locks").mkdir(parents=True)
    (state / "locks" / "0.output.lock").write_text("x")
    assert not stale_lock(state)  # no marker: unknown owner
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    marker = {"host": socket.gethostname(), "pid": int(dead.stdout)}
    (state / RUN_MARKER).write_text(json.dumps(marker))
    assert stale_lock(state)
    (state / RUN_MARKER).write_text(json.dumps({**marker, "host": "elsewhere"}))
    assert not stale_lock(state)
    (state / RUN_MARKER).write_text(json.dumps({**marker, "pid": os.getppid()}))  # alive
    assert not clear_stale_lock(state)
    mark_run(state)
    assert json.loads((state / RUN_MARKER).read_text())["pid"] == os.getpid()
    assert not stale_lock(state)  # this process
    (state / RUN_MARKER).write_text(json.dumps(marker))
    assert clear_stale_lock(state) and not any((state / "locks").iterdir())
