"""Whether a process still runs: the test behind stale locks and stale temporaries."""

from __future__ import annotations

import os


def process_exists(pid: int) -> bool:
    """Whether process ``pid`` runs on this machine (one of another user counts).

    A value that is not a process id (0 or negative, which ``os.kill`` would read as a
    process group) is never judged dead.

    Examples
    --------
    >>> process_exists(os.getpid())
    True
    >>> process_exists(0)
    True
    """
    if pid <= 0:
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
