"""Where the workflow lives, and how a job environment reinstalls this stereovar.

An installed wheel carries the workflow inside the package, at ``stereovar/_workflow``, laid
out as the checkout is (``Snakefile``, ``config.yaml``, ``workflow/``, ``envs/``,
``profiles/``); a checkout (``pip install -e .``) runs its own. Either way the results go
under the directory a command runs in, the working directory Snakemake is given.

Nothing here imports a third-party module: the Snakefile and the command line read it before
anything else.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from .errors import StereovarError

__all__ = [
    "PACKAGED",
    "REQUIREMENT_ENV",
    "default_configfile",
    "export_install_requirement",
    "install_requirement",
    "preset_path",
    "presets",
    "workflow_root",
]

#: The workflow's folder inside an installed package.
PACKAGED = "_workflow"
#: The environment variable the Snakefile sets to :func:`install_requirement`, read by the
#: conda environment's post-deploy script (``envs/stereovar.post-deploy.sh``).
REQUIREMENT_ENV = "STEREOVAR_REQUIREMENT"


def _is_workflow(folder: Path) -> bool:
    return (folder / "Snakefile").is_file() and (folder / "workflow" / "rules").is_dir()


def workflow_root(package: Path | None = None) -> Path:
    """The folder that holds the workflow's ``Snakefile``.

    The installed package's ``_workflow`` folder if it has one (a wheel), else the checkout
    the package is imported from (``src/stereovar`` two levels below it).

    Parameters
    ----------
    package : Path, optional
        The ``stereovar`` package folder; default: this module's.

    Raises
    ------
    StereovarError
        When neither holds a workflow (a broken installation).

    Examples
    --------
    >>> (workflow_root() / "Snakefile").is_file()
    True
    """
    package = Path(package or Path(__file__).resolve().parent)
    for folder in (package / PACKAGED, package.parent.parent):
        if _is_workflow(folder):
            return folder
    raise StereovarError(
        f"this stereovar ({package}) holds no workflow: neither {package / PACKAGED} nor a "
        "checkout around it has a Snakefile; reinstall it from a wheel or a checkout"
    )


def default_configfile(basedir) -> str:
    """The config the Snakefile reads first: ``config.yaml`` of the working directory when it
    has one (as in the checkout), else the workflow's own defaults (``basedir``'s).

    Examples
    --------
    >>> import os, tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     here = os.getcwd(); os.chdir(d)
    ...     try:
    ...         print(default_configfile("/opt/wf"))
    ...         open("config.yaml", "w").close(); print(default_configfile("/opt/wf"))
    ...     finally:
    ...         os.chdir(here)
    /opt/wf/config.yaml
    config.yaml
    """
    if Path("config.yaml").is_file():
        return "config.yaml"
    return str(Path(basedir) / "config.yaml")


def presets(root: Path | None = None) -> list[str]:
    """Names of the workflow's presets (``workflow/presets/<name>.yaml``, subfolders included:
    ``generators/kubric``)."""
    folder = Path(root or workflow_root()) / "workflow" / "presets"
    return sorted(p.relative_to(folder).with_suffix("").as_posix() for p in folder.rglob("*.yaml"))


def preset_path(name: str, root: Path | None = None) -> Path:
    """The config file of preset ``name``; one line listing the presets for an unknown one."""
    root = Path(root or workflow_root())
    path = root / "workflow" / "presets" / f"{name}.yaml"
    if not path.is_file():
        raise StereovarError(
            f"no preset {name!r}; use one of: {', '.join(presets(root)) or '(none)'}"
        )
    return path


def install_requirement(distribution=None) -> str:
    """A pip requirement that installs this stereovar again, for a job's own environment.

    Read from the installation's record (PEP 610 ``direct_url.json``): a checkout or folder
    (editable or not) gives its path, a wheel or archive file gives that file, a VCS install
    gives its URL and commit; an install from an index gives ``stereovar==<version>``.

    Parameters
    ----------
    distribution : importlib.metadata.Distribution, optional
        Default: the installed ``stereovar``.

    Examples
    --------
    >>> class Dist:
    ...     version = "0.1.0"
    ...     def __init__(self, url): self.url = url
    ...     def read_text(self, name): return self.url and json.dumps(self.url)
    >>> install_requirement(Dist({"url": "file:///src/stereovar", "dir_info": {}}))
    '/src/stereovar'
    >>> install_requirement(Dist({"url": "file:///w/stereovar-0.1.0-py3-none-any.whl",
    ...                           "archive_info": {}}))
    '/w/stereovar-0.1.0-py3-none-any.whl'
    >>> install_requirement(Dist(None))
    'stereovar==0.1.0'
    """
    from urllib.parse import unquote, urlparse

    if distribution is None:
        from importlib.metadata import PackageNotFoundError
        from importlib.metadata import distribution as find

        try:
            distribution = find("stereovar")
        except PackageNotFoundError as err:
            raise StereovarError(
                "stereovar is imported but not installed; install it (pip install -e . in the "
                "checkout) so that job environments can install it too"
            ) from err
    text = distribution.read_text("direct_url.json")
    if not text:
        return f"stereovar=={distribution.version}"
    record = json.loads(text)
    url = record["url"]
    if "vcs_info" in record:
        vcs = record["vcs_info"]
        return f"stereovar @ {vcs['vcs']}+{url}@{vcs.get('commit_id', '')}".rstrip("@")
    parsed = urlparse(url)
    if parsed.scheme == "file":
        return os.path.normpath(unquote(parsed.path))
    return f"stereovar @ {url}"


def export_install_requirement(environ) -> None:
    """Set :data:`REQUIREMENT_ENV` in ``environ`` to :func:`install_requirement`, unless it is
    set already or stereovar is not installed (the post-deploy script then says so)."""
    if REQUIREMENT_ENV in environ:
        return
    try:
        environ[REQUIREMENT_ENV] = install_requirement()
    except StereovarError:
        pass
