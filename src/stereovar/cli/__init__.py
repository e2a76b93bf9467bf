# PYTHON_ARGCOMPLETE_OK
"""Command-line interface: ``stereovar <group> <command> ...``.

Commands are grouped with argparse subparsers, one module per group:

- :mod:`~stereovar.cli.workflow` -- ``init``, ``run`` and ``report``;
- :mod:`~stereovar.cli.scenes` -- ``scenes generate`` and ``scenes validate``;
- :mod:`~stereovar.cli.audit` -- ``audit`` and ``export``;
- :mod:`~stereovar.cli.probe` -- ``probe``;
- :mod:`~stereovar.cli.sample` -- ``sample``: a re-render plan for one render per view;
- :mod:`~stereovar.cli.completion` -- ``completion``: the shell's tab completion;
- :mod:`~stereovar.cli.snakemake` -- what they share: the folder they work in, the
  workflow's folder and config, Snakemake's options on a command's line, and running
  Snakemake;
- :mod:`~stereovar.cli.monitor` -- how a command follows a Snakemake run (the logger
  plugin ``stereovar``: one line per stage, the errors of a failed run, and while the run is
  quiet its status again, its estimate counted down);
- :mod:`~stereovar.cli.console` -- what every command prints through: the program's name
  and ``say``, which escapes control characters;
- ``__main__`` -- ``python -m stereovar.cli``.

To add a group (e.g. ``stereovar backend``), write a module with a
``_register_<group>(subparsers)`` function that adds its parser and sets ``func=<handler>``
on each leaf command, and call it from :func:`build_parser`. Handlers take the parsed
namespace and return an exit status. Heavy modules (numpy, mitsuba, ...) are imported inside
the handlers so that ``stereovar --help`` stays fast.

``run`` and ``report`` pass the options they do not take themselves on to Snakemake, as
they do the words after ``--`` (``stereovar run -n`` is ``stereovar run -- -n``;
:func:`~stereovar.cli.snakemake.split_snakemake_options`); every other command refuses an
option it does not know.

Every :class:`~stereovar.errors.StereovarError` is printed as one line,
``stereovar: error: <message>``, on stderr and the exit status is 2. A bare ``stereovar``
prints the help, with examples and the documentation's address, and exits 0.
"""

from __future__ import annotations

import argparse
import os
import shlex
import sys
import types

# ``name as name``: re-exported, reached through the package: the constants, the run's
# monitor, its hook and the audit's log file, and the workflow's config. Snakemake's runner,
# ``_snakemake``, is :class:`_Package`'s.
from ..errors import StereovarError
from . import snakemake
from .audit import _audit_log as _audit_log
from .audit import _register_audit
from .completion import _register_completion
from .monitor import _Run as _Run
from .probe import _register_probe
from .sample import _register_sample
from .scenes import _register_scenes
from .snakemake import _MONITOR as _MONITOR
from .snakemake import PROG, _workflow, check_cores, say, split_snakemake_options
from .snakemake import _project_root as _project_root
from .snakemake import _workflow_config as _workflow_config
from .workflow import AUDIT_STARTER as AUDIT_STARTER
from .workflow import _register_workflow


class _Package(types.ModuleType):
    """This package, whose ``_snakemake`` (Snakemake's runner) is
    :data:`stereovar.cli.snakemake._RUNNER`, read and replaced there: replacing
    ``stereovar.cli._snakemake`` (a test's stand-in for Snakemake) replaces it for every
    command (:func:`stereovar.cli.snakemake._run_snakemake`), and no command's module
    imports the package for it."""

    @property
    def _snakemake(self):
        return snakemake._RUNNER

    @_snakemake.setter
    def _snakemake(self, runner) -> None:
        snakemake._RUNNER = runner


sys.modules[__name__].__class__ = _Package

#: The examples of ``stereovar --help``: command, what it does.
EXAMPLES = (
    ("stereovar init --example", "two synthetic frames and an audit.yaml for them, here"),
    ("stereovar audit audit.yaml", "audit them: one line per stage, then the verdict"),
    ("stereovar run -j2", "the default experiment on 2 cores, results under ./results"),
)


def _epilog() -> str:
    """The examples and the documentation's address (:func:`stereovar.links.docs_page`)."""
    from ..links import docs_page

    width = max(len(command) for command, _ in EXAMPLES)
    lines = [f"  {command:<{width}}  # {what}" for command, what in EXAMPLES]
    return "\n".join(["examples:", *lines, "", f"documentation: {docs_page('getting-started')}"])


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with one subparser per command group."""
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Cross-view Monte Carlo variance correlation in path-traced stereo.",
        epilog=_epilog(),
        # the examples' lines and --version's line unwrapped
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=_version())
    subparsers = parser.add_subparsers(dest="command", metavar="GROUP")
    _register_workflow(subparsers)
    _register_scenes(subparsers)
    _register_audit(subparsers)
    _register_probe(subparsers)
    _register_sample(subparsers)
    _register_completion(subparsers)
    return parser


def _version() -> str:
    """``stereovar <version> (workflow: <folder>)``."""
    from .. import __version__

    try:
        return f"{PROG} {__version__} (workflow: {_workflow()})"
    except StereovarError as err:
        return f"{PROG} {__version__} ({err})"


def main(argv=None) -> int:
    """Run the command line; returns (and, as a script, exits with) the exit status.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        0 on success (a bare ``stereovar``: the help), 2 on a usage error or a
        :class:`~stereovar.errors.StereovarError`, 130 when stopped by Ctrl-C; ``audit --fail-on``:
        :data:`~stereovar.cli.audit.FAIL_ON_STATUS` for a verdict at or past the level.
    """
    argv = given = list(sys.argv[1:] if argv is None else argv)
    passthrough = []
    if "--" in argv:  # snakemake's own options, for the commands that run it
        cut = argv.index("--")
        argv, passthrough = argv[:cut], argv[cut + 1 :]
    parser = build_parser()
    if "_ARGCOMPLETE" in os.environ:  # the shell asks for completions (stereovar completion)
        import argcomplete

        argcomplete.autocomplete(parser)  # answers and exits
    # run and report: the options they do not take are Snakemake's, as after --
    argv, unknown = split_snakemake_options(parser, argv)
    passthrough = [*unknown, *passthrough]
    args = parser.parse_args(argv)
    if args.command is None and not passthrough:
        parser.print_help()
        return 0
    if passthrough and not getattr(args, "passthrough", False):
        parser.error(
            "options after -- are for run and report only"
            + (f", not {args.command}" if args.command else "")
        )
    args.snakemake_args = passthrough
    args.command_line = shlex.join([PROG, *given])
    try:
        check_cores(getattr(args, "cores", None))
        return int(args.func(args) or 0)
    except StereovarError as err:
        say(f"{PROG}: error: {' '.join(str(err).split())}")
        return 2
    except BrokenPipeError:  # output piped into e.g. `head`, which closed early
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:  # Ctrl-C outside a Snakemake run (which says it itself)
        from .monitor import INTERRUPTED, INTERRUPTED_STATUS

        print(f"{PROG}: {INTERRUPTED}", file=sys.stderr)
        return INTERRUPTED_STATUS
