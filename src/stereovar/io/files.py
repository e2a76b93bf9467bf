"""Opening a user's files: regular files only, each failure one line.

A named pipe, a device or a directory is refused by its kind before it is opened for reading
(:func:`regular_file`, :func:`open_regular`), so nothing waits on a pipe that no one writes to;
each failure is one :class:`~stereovar.errors.ImageError` line naming the file and the fix, and
what the libraries print themselves about a damaged file is silenced.
"""

from __future__ import annotations

import os
import stat
from contextlib import ExitStack, contextmanager

from ..errors import ImageError
from ..renderers.quiet import silenced
from .formats import image_format

_KINDS = {
    stat.S_IFIFO: "a named pipe",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFDIR: "a directory",
    stat.S_IFSOCK: "a socket",
}


def _unreadable(path, err, what="file") -> ImageError:
    detail = " ".join(str(err).split())[:160]
    return ImageError(
        f"{path}: cannot read the {what} ({detail}); it is truncated or not a valid "
        f"{image_format(path).upper()} file: write it again"
    )


def file_kind(mode: int) -> str:
    """What a file that is not a regular one is, in words, from its ``st_mode``.

    Parameters
    ----------
    mode : int
        The file's ``st_mode`` (:func:`os.stat`, :func:`os.fstat`).

    Returns
    -------
    str
        ``"a named pipe"``, ``"a character device"``, ``"a block device"``, ``"a
        directory"``, ``"a socket"``, or ``"not a file"``.

    Examples
    --------
    >>> file_kind(stat.S_IFIFO | 0o644), file_kind(stat.S_IFDIR | 0o755)
    ('a named pipe', 'a directory')
    """
    return _KINDS.get(stat.S_IFMT(mode), "not a file")


def not_regular_error(path, mode) -> ImageError:
    """The one-line error for ``path`` whose ``st_mode`` is ``mode``: not a regular file."""
    return ImageError(
        f"{path}: not a regular file ({file_kind(mode)}); give the path of an image file"
    )


def unopenable_error(path, err: OSError) -> ImageError:
    """The one-line error for a ``path`` that cannot be opened (``err``): missing
    (:func:`missing_error`) or not readable."""
    if isinstance(err, FileNotFoundError):
        return missing_error(path)
    return ImageError(f"{path}: cannot open it ({err.strerror}); make it readable")


def missing_error(path) -> ImageError:
    """The one-line error for a ``path`` that does not exist."""
    return ImageError(f"{path}: no such file; check the audit path template")


def regular_file(path) -> None:
    """Check that ``path`` is a regular file (a link to one counts) without opening it.

    Raises
    ------
    ImageError
        It does not exist (or is a dangling link), or it is a named pipe, a device, a
        directory or a socket (one line naming the kind).
    """
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise missing_error(path) from None
    except OSError as err:
        raise ImageError(f"{path}: cannot look at it ({err.strerror}); fix its path") from None
    if not stat.S_ISREG(mode):
        raise not_regular_error(path, mode)


@contextmanager
def open_regular(path, *, unopenable=unopenable_error, not_regular=not_regular_error):
    """``path`` opened for binary reading once it is known to be a regular file: the open
    does not block (a named pipe opened for reading would wait for a writer) and the kind
    is checked on the open descriptor, so what is read is the file that was checked.

    Parameters
    ----------
    path : path-like
    unopenable : callable (path, OSError) -> Exception, keyword-only
        The error raised when ``path`` cannot be opened (default: an image file's,
        :func:`unopenable_error`).
    not_regular : callable (path, int) -> Exception, keyword-only
        The error raised for a path whose ``st_mode`` is not a regular file's (default: an
        image file's, :func:`not_regular_error`; :func:`file_kind` names the kind).

    Yields
    ------
    io.BufferedReader
        The open file, closed on leaving the block.
    """
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as err:
        raise unopenable(path, err) from None
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        raise not_regular(path, mode)
    os.set_blocking(fd, True)
    with os.fdopen(fd, "rb") as f:
        yield f


@contextmanager
def _quiet():
    """Silence stdout and stderr while a library reads a file: OpenEXR and libpng print
    their own diagnostics of a damaged file there (OpenEXR's bindings also through Python's
    ``sys.stdout``)."""
    with ExitStack() as stack:
        for fd in (1, 2):
            stack.enter_context(silenced(fd, python=True))
        yield


@contextmanager
def reading_header(path):
    """Any library's failure to read the header of ``path`` inside the block as one
    :class:`ImageError` line: the file is truncated or not of its extension's format (an
    HDF5 file cut short cannot be opened at all, so its datasets cannot be listed).

    Parameters
    ----------
    path : path-like
        The file whose header the block reads, named in the line.

    Raises
    ------
    ImageError
        ``path: cannot read the header (<the library's words>); it is truncated or not a
        valid <FORMAT> file: write it again``; an :class:`ImageError` raised inside passes
        as it is.

    Examples
    --------
    >>> with reading_header("a/0.hdf5"):  # doctest: +ELLIPSIS
    ...     raise OSError("Unable to synchronously open file (file signature not found)")
    Traceback (most recent call last):
    ...
    stereovar.errors.ImageError: a/0.hdf5: cannot read the header (Unable to ... not found)); ...
    """
    try:
        yield
    except ImageError:
        raise
    except Exception as err:  # each library raises its own exception types
        raise _unreadable(path, err, "header") from None
