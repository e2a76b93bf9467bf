"""Exception types whose message is a single line naming the problem and the fix."""

from contextlib import contextmanager


class StereovarError(Exception):
    """Base class for every error the tool reports to a user.

    The message is one line: what is wrong, where, and how to fix it. Command-line entry
    points and Snakemake scripts print it without a traceback.
    """


class ConfigError(StereovarError):
    """A config key, type or value is invalid."""


class SceneError(StereovarError):
    """A scene spec or a referenced scene file is missing or invalid."""


class BackendError(StereovarError):
    """No usable Mitsuba variant, or a forced variant is unavailable."""


class StoreError(StereovarError):
    """A stored result (e.g. a render) is missing, damaged or incomplete and must be rerun."""


class MatcherFileError(StoreError, ValueError):
    """A path that is not a probe network written by
    :func:`stereovar.probe.training.save_matcher` (missing, not a regular file, not such a
    file, or with non-finite weights); a job reports it in one line."""


class WriteError(StereovarError):
    """A result cannot be written (a full disk, a read-only folder); what was written before
    is kept, and the same command resumes once the cause is fixed."""


class RunLockedError(StereovarError):
    """Another ``stereovar`` command holds the lock of the results this one would write
    (:mod:`stereovar.run_lock`)."""


class ImageError(StereovarError):
    """An image, disparity, depth or mask file cannot be read or has the wrong shape."""


class ClaimsError(StereovarError):
    """The claims file (the paper's claims the claims table tests) is missing or malformed."""


class AuditError(StereovarError):
    """An audit's files do not form N >= 2 renders per view of stereo frames with ground
    truth, or their disparity convention is the wrong one."""


def printable(text) -> str:
    r"""``text`` safe to print on a terminal: every character that is not printable (the
    terminal's control characters, such as ESC and BEL, which can retitle the window or
    erase lines, newlines and tabs, and invisible format characters such as bidirectional
    overrides) written as its Python escape; the rest, letters of every script included,
    unchanged.

    Examples
    --------
    >>> printable("data/e\x1b]0;TITLE\x07/f.exr")
    'data/e\\x1b]0;TITLE\\x07/f.exr'
    >>> printable("renders/café/L.exr: no such file")
    'renders/café/L.exr: no such file'
    """
    return "".join(
        c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in str(text)
    )


@contextmanager
def exit_with_one_line():
    """Turn a :class:`StereovarError` raised inside into ``SystemExit("stereovar: <message>")``.

    Inside a Snakefile, an exception makes Snakemake print its type, the file and line and a
    traceback of workflow frames; ``SystemExit`` with a message makes it print only the
    message (to stderr) and exit with status 1. Command-line entry points use it the same way.

    Examples
    --------
    >>> try:
    ...     with exit_with_one_line():
    ...         raise ConfigError("config key 'spp': 0 is too small; use at least 1")
    ... except SystemExit as stop:
    ...     print(stop.code)
    stereovar: config key 'spp': 0 is too small; use at least 1
    """
    try:
        yield
    except StereovarError as err:
        raise SystemExit(f"stereovar: {err}") from None
