"""Running the workflow: the folder a command works in, the workflow's folder and config,
and Snakemake itself.

Every command runs Snakemake through :func:`_run_snakemake`, which calls
``stereovar.cli._snakemake`` as the package holds it at call time: replacing that one name
(a test's stand-in for Snakemake) replaces it for every command.
"""

from __future__ import annotations

import contextvars
import sys

PROG = "stereovar"


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
    """Run ``snakemake --snakefile <workflow>/Snakefile ARGS`` in ``root``; its output goes to
    the terminal, or, while a command has set :data:`_MONITOR` (``stereovar audit``), through
    that monitor."""
    import subprocess

    snakefile = _workflow() / "Snakefile"
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(snakefile), *args]
    monitor = _MONITOR.get()
    if monitor is not None:
        return monitor.run(cmd, root)
    print("stereovar: running " + " ".join(cmd[1:]), file=sys.stderr)
    return subprocess.run(cmd, cwd=root, check=False).returncode


#: The :class:`_AuditMonitor` that :func:`_snakemake` runs Snakemake through, if any.
_MONITOR: contextvars.ContextVar = contextvars.ContextVar("stereovar_monitor", default=None)


def _workflow_config(root, files) -> dict:
    """The config the workflow would run with: ``config.yaml`` of ``root`` (else the
    workflow's own, as the Snakefile reads it), then ``files``
    (as ``--configfile``), validated against the workflow's schema with its defaults filled
    in (:func:`stereovar.config.load_config`); one line for anything it refuses."""
    from ..config import load_config

    workflow = _workflow()
    first = root / "config.yaml" if (root / "config.yaml").is_file() else workflow / "config.yaml"
    return load_config([first, *files], workflow / "workflow" / "schemas" / "config.schema.yaml")


def _run_snakemake(args: list, root) -> int:
    """``stereovar.cli._snakemake(args, root)``, looked up on the package when called."""
    from .. import cli

    return cli._snakemake(args, root)
