"""Silence a C-level file descriptor while native code prints to it (a renderer's progress
lines, an image library's diagnostics).

Standard library only, so that :mod:`stereovar.renderers.mitsuba.backend` stays importable
before any dependency is installed.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import os
import sys
import threading

_lock = threading.Lock()
_held: dict = {}
"""What overlapping :func:`silenced` blocks hold: key to ``[blocks inside, undo]``."""


@functools.cache
def _libc():
    try:
        return ctypes.CDLL(None)
    except OSError:  # no C library to load by that name
        return None


def _flush_c_stdio() -> None:
    """Flush the C library's stdio buffers, so text native code wrote while a descriptor was
    silenced goes where the descriptor pointed then."""
    libc = _libc()
    if libc is not None and hasattr(libc, "fflush"):
        libc.fflush(None)


@contextlib.contextmanager
def _shared(key, switch_on):
    """``switch_on()`` (which returns its undo) when the first of overlapping blocks with
    ``key`` enters, in any thread; the undo when the last one leaves."""
    with _lock:
        held = _held.get(key)
        if held is None:
            held = _held[key] = [0, switch_on()]
        held[0] += 1
    try:
        yield
    finally:
        with _lock:
            held[0] -= 1
            if held[0] == 0:
                del _held[key]
                held[1]()


def _to_devnull(fd: int):
    (sys.stdout if fd == 1 else sys.stderr).flush()
    _flush_c_stdio()
    saved = os.dup(fd)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, fd)
    except OSError:
        os.close(saved)
        raise
    finally:
        os.close(devnull)

    def undo():
        _flush_c_stdio()
        os.dup2(saved, fd)
        os.close(saved)

    return undo


def _python_stream_to_devnull(fd: int):
    name = "stdout" if fd == 1 else "stderr"
    stream = getattr(sys, name)
    sink = open(os.devnull, "w")  # noqa: SIM115 (closed by the undo)
    setattr(sys, name, sink)

    def undo():
        setattr(sys, name, stream)
        sink.close()

    return undo


@contextlib.contextmanager
def silenced(fd: int, enabled: bool = True, *, python: bool = False):
    """Point file descriptor ``fd`` (1: stdout, 2: stderr) at /dev/null while the block runs;
    Python's own stream is flushed first and the descriptor restored afterwards.

    Blocks may overlap, also in several threads (images decoded by a thread pool): the
    descriptor is silenced when the first one enters and restored when the last one leaves,
    which silences the whole process's output on ``fd`` in between.

    Parameters
    ----------
    fd : {1, 2}
    enabled : bool
        False runs the block as it is.
    python : bool, keyword-only
        Also replace ``sys.stdout`` (``sys.stderr``) by a sink: for native code that prints
        through Python's stream (pybind11's ``py::print``, as the OpenEXR bindings do).
    """
    if not enabled:
        yield
        return
    with contextlib.ExitStack() as stack:
        stack.enter_context(_shared(("fd", fd), lambda: _to_devnull(fd)))
        if python:
            stack.enter_context(_shared(("python", fd), lambda: _python_stream_to_devnull(fd)))
        yield
