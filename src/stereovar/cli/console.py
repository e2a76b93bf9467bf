"""What every command prints through: the program's name and :func:`say`, which escapes the
terminal's control characters in a user's text. Both :mod:`~stereovar.cli.snakemake` and
:mod:`~stereovar.cli.monitor` print through it, so that neither imports the other for it."""

from __future__ import annotations

import sys

PROG = "stereovar"


def say(text: str, stream=None) -> None:
    """Print ``text`` (lines) with the terminal's control characters in a user's paths and
    names escaped (:func:`stereovar.errors.printable`): every command prints what holds a
    user's text through it.

    Parameters
    ----------
    text : str
        One line or several.
    stream : file, optional
        Default: stderr.
    """
    from ..errors import printable

    print("\n".join(map(printable, str(text).split("\n"))), file=stream or sys.stderr)


def isatty(stream) -> bool:
    """Whether ``stream`` is a terminal; False for a stream that cannot say (closed, or no
    ``isatty``)."""
    try:
        return stream.isatty()
    except (AttributeError, ValueError, OSError):
        return False
