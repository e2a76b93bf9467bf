"""The lock a ``stereovar`` command holds, for its whole run, over the results it may write.

Snakemake locks the files a run reads and writes (``.snakemake/locks``), but a run that ends
removes that whole folder, the locks of runs still going in the same folder included; a
third run is then not refused and writes beside the first, over its outputs. So
``stereovar run``, ``audit``, ``probe`` and ``export`` each hold a lock of their own, an
exclusive ``flock`` on a file Snakemake never touches (:func:`stereovar.layout.run_lock`),
from before their first write until they end. The kernel releases it when the process ends,
however it ends: a killed run leaves no lock behind to remove.

A lock covers a *scope*, the results a command may write (:func:`lock_scope`):

``audit-{name}``
    an audit's own results, ``results/audit/{name}/`` (and its logs);
``run``
    the workflow's results: renders, ground truth, statistics, tables, figures, pages, the
    probe and the export (``results/`` but the audits).

Two audits of different names write disjoint results and run side by side; a command that
would write a scope another command holds is refused before it writes anything, in one line
naming the holder: its process, when it started and its command (:class:`RunLock`).

A dry run writes nothing and takes no lock.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from .errors import RunLockedError, WriteError
from .layout import run_lock

RUN_SCOPE = "run"
"""The scope of the workflow's own results (every result but the audits')."""


def lock_scope(config: dict) -> str:
    """The scope of the results a run of ``config`` may write: ``audit-{name}`` for a config
    with an ``audit:`` section (the run is that audit), else :data:`RUN_SCOPE`.

    Parameters
    ----------
    config : dict
        The workflow config the run uses.

    Returns
    -------
    str

    Examples
    --------
    >>> lock_scope({"audit": {"name": "kitti"}}), lock_scope({"scenes": ["a"]})
    ('audit-kitti', 'run')
    """
    audit = config.get("audit") or {}
    return f"audit-{audit['name']}" if audit.get("name") else RUN_SCOPE


def scope_results(scope: str, root=".") -> str:
    """What a scope's results are, for a message: the folder and what it holds.

    Examples
    --------
    >>> scope_results("audit-kitti", "/data")
    "the audit kitti's results (/data/results/audit/kitti)"
    >>> scope_results("run", "/data")
    "the workflow's results (/data/results, the audits' aside)"
    """
    results = Path(root) / "results"
    if scope.startswith("audit-"):
        name = scope[len("audit-") :]
        return f"the audit {name}'s results ({results / 'audit' / name})"
    return f"the workflow's results ({results}, the audits' aside)"


def _read_holder(fd: int) -> dict | None:
    """The holder's record in the lock file (None while it is being written)."""
    try:
        data = json.loads(os.pread(fd, 1 << 16, 0).decode("utf-8", "replace"))
        return {**data, "pid": int(data["pid"]), "host": str(data["host"])}
    except (OSError, ValueError, KeyError, TypeError):
        return None


class RunLock:
    """An exclusive lock on one scope's results for the life of a command.

    Use it as a context manager; entering it takes the lock or refuses the command.

    Parameters
    ----------
    root : path-like
        The folder the command works in (its ``results/`` holds the lock file).
    scope : str
        :func:`lock_scope` of the run's config.
    command : str
        The command line, recorded in the lock file for a command it refuses.

    Attributes
    ----------
    warning : str or None
        Why the lock could not be taken where the file system has no locks (some network
        file systems): the run goes on unlocked, and the command says so.

    Raises
    ------
    RunLockedError
        On entry, when another process holds the scope: one line naming it (its pid, host
        when another, start time and command) and to wait for it.
    WriteError
        On entry, when the lock file cannot be created.

    Examples
    --------
    >>> import tempfile
    >>> root = tempfile.mkdtemp()
    >>> with RunLock(root, "audit-a", "stereovar audit a.yaml"):
    ...     with RunLock(root, "audit-b", "stereovar audit b.yaml"):
    ...         pass  # another scope: both held at once
    """

    def __init__(self, root, scope: str, command: str):
        self.root, self.scope, self.command = Path(root), scope, command
        self.path = self.root / run_lock(scope)
        self.fd: int | None = None
        self.warning: str | None = None

    def __enter__(self) -> RunLock:
        import fcntl

        from .preflight import process_record

        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
        except OSError as err:
            from .preflight import check_writable

            check_writable([self.path.parent])  # read-only, immutable, not the user's: said so
            raise WriteError(
                f"{self.path}: cannot create the run's lock file ({err.strerror or err}); make "
                f"{self.path.parent} writable, then run the same command again"
            ) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _read_holder(fd)
            os.close(fd)
            raise RunLockedError(self.refusal(holder)) from None
        except OSError as err:  # a file system without locks: the run goes on unlocked
            os.close(fd)
            self.warning = (
                f"{self.path}: this file system takes no lock ({err.strerror or err}), so a "
                "second run here would not be refused; run one command at a time in this folder"
            )
            return self
        record = json.dumps(process_record(os.getpid(), self.command)).encode()
        os.ftruncate(fd, 0)
        os.pwrite(fd, record, 0)
        self.fd = fd
        return self

    def __exit__(self, *exc) -> None:
        if self.fd is not None:
            import fcntl

            try:
                os.ftruncate(self.fd, 0)  # no holder named once it is free
                fcntl.flock(self.fd, fcntl.LOCK_UN)
            finally:
                os.close(self.fd)
                self.fd = None

    def refusal(self, holder: dict | None) -> str:
        """The line that refuses a command while ``holder`` (its record) holds the scope."""
        from .preflight import describe_run

        who = f" ({describe_run(holder)})" if holder else ""
        return (
            f"{scope_results(self.scope, self.root.absolute())} are being written by another "
            f"stereovar run{who}; wait for it to finish, then run the same command again"
        )
