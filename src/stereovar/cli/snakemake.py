"""Running the workflow: the folder a command works in, the workflow's folder and config,
Snakemake's own options on a command's line, and Snakemake itself.

Every command runs Snakemake through :func:`_run_snakemake`, which calls :data:`_RUNNER` as
it is at call time; the package's ``stereovar.cli._snakemake`` is that name, read and
replaced here, so that replacing it (a test's stand-in for Snakemake) replaces it for every
command.
"""

from __future__ import annotations

import contextvars
import sys

from ..errors import StereovarError

# ``name as name``: what every command prints through, reached here by the command modules.
from .console import PROG as PROG
from .console import say as say


def check_cores(cores) -> None:
    """Refuse a ``-j`` below 1, which Snakemake would wait on for ever (``Provided cores:
    0``); every command that runs Snakemake takes ``-j`` and is checked here, before any work.
    None (a command without ``-j``) passes.

    Examples
    --------
    >>> check_cores(2), check_cores(None)
    (None, None)
    >>> check_cores(0)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    stereovar.errors.StereovarError: -j 0: a run needs at least 1 core; give -j 1 or more ...
    """
    if cores is not None and cores < 1:
        raise StereovarError(
            f"-j {cores}: a run needs at least 1 core; give -j 1 or more (e.g. -j 2)"
        )


def _project_root():
    """The directory a command works in: the current one. Configs' relative paths, results,
    logs and Snakemake's state are all relative to it, as for ``snakemake``; the workflow
    itself is the installed package's or the checkout's (:func:`_workflow`)."""
    from pathlib import Path

    return Path.cwd()


def _workflow():
    """The folder of the workflow's Snakefile (:func:`stereovar.workflow_home.workflow_root`)."""
    from ..workflow_home import workflow_root

    return workflow_root()


def _snakemake(args: list, root) -> int:
    """Run ``snakemake --snakefile <workflow>/Snakefile ARGS`` in ``root``.

    While a command has set :data:`_MONITOR` (``stereovar audit``), through that
    :class:`~stereovar.cli.monitor._Run`; else, for a run of jobs (or a dry run), through a
    new one (:func:`_run_with_progress`): one line per stage, Snakemake's whole output in a
    new log file; else (options that run nothing, such as ``--unlock``) with Snakemake's own
    output on the terminal (:func:`_run_plain`)."""
    from ..progress import reports_progress

    snakefile = _workflow() / "Snakefile"
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(snakefile), *args]
    monitor = _MONITOR.get()
    if monitor is not None:
        return monitor.run(cmd, root)
    if reports_progress(args):
        return _run_with_progress(cmd, root)
    print("stereovar: running " + " ".join(cmd[1:]), file=sys.stderr)
    return _run_plain(cmd, root)


def _run_plain(cmd: list, root) -> int:
    """Run ``cmd`` (Snakemake) in ``root`` with its own output, stdout and stderr, on the
    command's, as it comes; but where Snakemake refuses its options (argparse's ``usage:``
    and error), one line that says so (:func:`~stereovar.cli.monitor.usage_error`). Returns
    its exit status."""
    import subprocess

    from .monitor import usage_error

    held = []  # from a usage line on: a refusal of the options, said once Snakemake stopped
    with subprocess.Popen(
        cmd, cwd=root, stderr=subprocess.PIPE, text=True, errors="replace"
    ) as proc:
        try:
            for line in proc.stderr:
                if held or line.startswith("usage: "):
                    held.append(line)
                else:
                    sys.stderr.write(line)
                    sys.stderr.flush()
            rc = proc.wait()
        except KeyboardInterrupt:  # the terminal's Ctrl-C reached Snakemake too: it stops
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
            raise
    message = usage_error(held)
    if message:
        say(f"{PROG}: error: {message}")
    else:
        sys.stderr.writelines(held)
    return rc


#: The :class:`~stereovar.cli.monitor._Run` that :func:`_snakemake` runs Snakemake through,
#: if a command has set one.
_MONITOR: contextvars.ContextVar = contextvars.ContextVar("stereovar_monitor", default=None)

#: Whether the command asked for Snakemake's whole output live (``-v``).
_VERBOSE: contextvars.ContextVar = contextvars.ContextVar("stereovar_verbose", default=False)


def _new_log(folder, stem: str):
    """A new log file ``<folder>/<stem>-<time>.log`` (never one that exists): its path and
    the file, open for writing."""
    import time

    stem = f"{stem}-{time.strftime('%Y%m%d-%H%M%S')}"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        for k in range(1, 1000):
            path = folder / f"{stem}{'' if k == 1 else f'-{k}'}.log"
            try:
                return path, open(path, "x", encoding="utf-8")  # noqa: SIM115 (caller closes)
            except FileExistsError:
                continue
    except OSError as err:
        raise StereovarError(
            f"{folder}: cannot create the run's log file there ({err.strerror or err}); "
            "make room or make it writable, then run the same command again"
        ) from None
    raise StereovarError(f"{folder}: cannot create a new log file there")


def _run_with_progress(cmd: list, root) -> int:
    """Run Snakemake (``cmd``) with one line per stage of the workflow
    (:data:`stereovar.stages.RUN_STAGES`) and its whole output in a new log file,
    ``logs/stereovar-run-<time>.log``; after the run, a failed run's errors (one line
    each) and the log's path; where Snakemake refused its options, only that line (the log,
    which holds nothing else, is removed)."""
    import os

    from .monitor import _Run, log_line

    path, log = _new_log(root / "logs", "stereovar-run")
    log.close()
    shown = os.path.relpath(path)
    run = _Run(path, stages="run", verbose=_VERBOSE.get(), command=" ".join([PROG, *sys.argv[1:]]))
    rc = run.run(cmd, root)
    run.report(rc)
    if rc and run.refusal():  # its options refused: the log holds only Snakemake's usage
        path.unlink(missing_ok=True)
        return rc
    say(log_line(shown, run.job_logs() if rc else ()))
    return rc


def _workflow_config(root, files) -> dict:
    """The config the workflow would run with: ``config.yaml`` of ``root`` (else the
    workflow's own, as the Snakefile reads it), then ``files``
    (as ``--configfile``), validated against the workflow's schema with its defaults filled
    in (:func:`stereovar.config.load_config`); one line for anything it refuses."""
    from ..config import load_config

    workflow = _workflow()
    first = root / "config.yaml" if (root / "config.yaml").is_file() else workflow / "config.yaml"
    return load_config([first, *files], workflow / "workflow" / "schemas" / "config.schema.yaml")


def _hold_results(root, config: dict, command: str, snakemake_args=()):
    """A context that holds the lock of the results a run of ``config`` may write
    (:class:`stereovar.run_lock.RunLock`, its scope :func:`~stereovar.run_lock.lock_scope`)
    for as long as the command goes; another command holding them refuses this one, in one
    line, before anything is written. A dry run writes nothing and takes none, nor do
    Snakemake options that run no job, but ``--unlock``, which removes the locks of the runs
    going in the folder."""
    from contextlib import nullcontext

    from ..progress import is_dry_run, reports_progress
    from ..run_lock import RunLock, lock_scope

    args = list(snakemake_args)
    if is_dry_run(args) or not (reports_progress(args) or "--unlock" in args):
        return nullcontext()
    return RunLock(root, lock_scope(config), command)


def _warn_unlocked(lock) -> None:
    """Say when the run goes on without its lock (a file system without locks)."""
    if getattr(lock, "warning", None):
        say(f"warning: {lock.warning}")


def _passed_configfiles(snakemake_args) -> list:
    """The config files among Snakemake's own options (``-- --configfile a.yaml b.yaml``)."""
    files, taking = [], False
    for arg in snakemake_args:
        name, eq, value = arg.partition("=")
        if name in ("--configfile", "--configfiles"):
            taking = not eq
            files += [value] if eq else []
        elif arg.startswith("-"):
            taking = False
        elif taking:
            files.append(arg)
    return files


def _run_snakemake(args: list, root) -> int:
    """``stereovar.cli._snakemake(args, root)``: :data:`_RUNNER`, looked up when called."""
    return _RUNNER(args, root)


#: What :func:`_run_snakemake` runs Snakemake with: :func:`_snakemake`, or what replaced it
#: as ``stereovar.cli._snakemake`` (the package reads and replaces this name).
_RUNNER = _snakemake


def split_snakemake_options(parser, argv: list) -> tuple:
    """``argv`` (the words before any ``--``) split into the command's own and Snakemake's,
    for a command whose parser sets ``passthrough`` (``run``, ``report``).

    An option the command's parser names, in full, is the command's, with its value (``-j
    4``, ``-j4``, ``--configfile=a.yaml``); every other option is Snakemake's, and so is each
    word after Snakemake's first option (a value of it, or a target, as Snakemake reads
    them: ``-R render``); the words before it are the command's (its targets). So ``stereovar
    run -n mitigations`` is ``stereovar run mitigations -- -n`` and ``stereovar run -R
    render`` is ``stereovar run -- -R render``. Other commands' words are left whole: their
    parser refuses what it does not know.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The top-level parser (:func:`stereovar.cli.build_parser`).
    argv : list of str
        The words after the program's name, before any ``--``.

    Returns
    -------
    tuple of list
        The command's words (the group name included) and Snakemake's, each in order.
    """
    import argparse

    commands = {}
    for action in parser._actions:  # argparse lists a parser's subcommands nowhere public
        if isinstance(action, argparse._SubParsersAction):
            commands.update(action.choices)
    at = next((k for k, word in enumerate(argv) if not word.startswith("-")), None)
    command = commands.get(argv[at]) if at is not None else None
    if command is None or not command.get_default("passthrough"):
        return list(argv), []
    # each option of the command: whether it takes a value
    owned = {name: action.nargs != 0 for action in command._actions
             for name in action.option_strings}
    ours, theirs = list(argv[: at + 1]), []
    words = iter(argv[at + 1 :])
    for word in words:
        if not word.startswith("-") or word == "-":
            (theirs if theirs else ours).append(word)
            continue
        name = word.split("=", 1)[0] if word.startswith("--") else word[:2]
        takes_value = owned.get(name)
        if takes_value is None:
            theirs.append(word)
            continue
        if not takes_value and word != name:  # -vn: stereovar's -v, Snakemake's -n
            command.error(
                f"{word}: {name} is stereovar's option; give it apart from Snakemake's "
                f"(e.g. {name} -{word[2:]})"
            )
        ours.append(word)
        if takes_value and word == name:
            value = next(words, None)  # its value, the next word (argparse checks it)
            if value is not None:
                ours.append(value)
    return ours, theirs
