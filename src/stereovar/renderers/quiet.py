"""Silence a C-level file descriptor while a renderer's native code prints to it.

Standard library only, so that :mod:`stereovar.renderers.mitsuba.backend` stays importable
before any dependency is installed.
"""

from __future__ import annotations

import contextlib
import os
import sys


@contextlib.contextmanager
def silenced(fd: int, enabled: bool = True):
    """Point file descriptor ``fd`` (1: stdout, 2: stderr) at /dev/null while the block runs;
    Python's own stream is flushed first and the descriptor restored afterwards."""
    if not enabled:
        yield
        return
    (sys.stdout if fd == 1 else sys.stderr).flush()
    saved = os.dup(fd)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, fd)
        yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)
        os.close(devnull)
