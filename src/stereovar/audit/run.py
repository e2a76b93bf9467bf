"""An audit as a workflow run: import, the run's config, and its targets.

``workflow/rules/common.smk`` calls :func:`discover_audit` when the config has an ``audit:``
section (the files are found, not read), then replaces the run's scenes, renderer, N and SPP
with the audit's (:func:`audit_run_config`), so every rule downstream of the renders (Eq. 1-3,
the controls, the intervention, the tables) runs unchanged on the imported stores. The import
is one job per frame (rule ``audit_import``: its inputs are :func:`frame_files`, its outputs
:func:`import_outputs`, its params :func:`import_params`); ``all`` builds
:func:`audit_targets`, ending in the verdict page. ``stereovar audit`` makes the workflow's
checks of an audit before Snakemake starts (:func:`check_audit_run`); a run that rebuilds the
verdict first sets the old one aside (:func:`set_aside_verdict`).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from .. import layout
from .. import resources as sizing
from ..errors import AuditError, ImageError
from ..experiment import audit_source, ground_truth_store
from ..io.files import regular_file
from ..io.headers import image_size
from ..layout import import_record
from ..rig import VIEWS
from .hashing import frame_fingerprint
from .layout import Discovery, discover
from .settings import audit_spp, check_settings, frame_stores, import_settings, settings_digest


def discover_audit(settings: dict) -> Discovery:
    """What the workflow does with an audit's files while it is parsed: find them.

    The settings that need no file are checked (:func:`check_settings`, the numbers of
    :func:`~stereovar.audit.settings.import_settings`) and the templates are globbed
    (:func:`~stereovar.audit.layout.discover`: templates that match nothing, view names,
    missing ground truth, seed counts); no file is opened, hashed or decoded and nothing is
    written. The import is a job per frame (rule ``audit_import``,
    :func:`stereovar.audit.importer.import_frame`).

    Parameters
    ----------
    settings : dict
        The ``audit:`` section of the config: ``name``, the ``renders`` template (fields
        ``{frame}``, ``{view}``, ``{seed}``), ``views``, the ground truth's templates
        (``disparity`` or ``depth``) and the ``convention``.

    Returns
    -------
    Discovery
        The frames in name order, each with its render and ground-truth files.

    Raises
    ------
    AuditError, ImageError
        One line naming the setting or file and the fix.

    Examples
    --------
    ``stereovar audit CONFIG`` starts here. Two synthetic frames
    (:func:`~stereovar.audit.synthetic.write_synthetic_audit`: 32 x 16 EXR renders, 2 views
    x 4 seeds, and a PFM disparity per frame) written to a temporary folder, with the
    ``audit:`` settings that read them. The audit finds the files without reading a pixel,
    and the run takes its scenes, resolution and N from them (:func:`audit_run_config`):

    >>> import tempfile
    >>> from stereovar.audit.synthetic import write_synthetic_audit
    >>> folder = tempfile.TemporaryDirectory()
    >>> settings, _ = write_synthetic_audit(folder.name, width=32, height=16, n_seeds=4)
    >>> sorted(settings)
    ['convention', 'disparity', 'name', 'renders', 'views']
    >>> discovery = discover_audit(settings)
    >>> discovery.summary()
    '2 frames × 2 views × 4 seeds'
    >>> config = {"audit": settings, "rig": {}, "render": {}, "intervention": {}}
    >>> run = audit_run_config(config, discovery)
    >>> run["scenes"], run["resolution"], run["render"]["n_seeds"]
    (['f00', 'f01'], {'width': 32, 'height': 16}, 4)
    >>> audit_paths(settings["name"])["verdict_html"]
    'results/audit/synthetic/verdict.html'

    A setting that cannot work stops the audit before any file is read, in one line:

    >>> discover_audit({**settings, "convention": "sideways"})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    stereovar.errors.AuditError: audit.convention 'sideways' is unknown; use paper ...
    >>> folder.cleanup()
    """
    check_settings(settings)
    import_settings(settings)
    discovery = discover(settings)
    check_files(discovery)
    return discovery


def check_files(discovery: Discovery) -> None:
    """Every file of the audit is a regular file this user may read, from its kind and
    permissions alone (nothing is opened): a named pipe, a device or an unreadable file
    found by the import job itself would stop the run after Snakemake had deleted the
    frame's earlier stores.

    Parameters
    ----------
    discovery : Discovery
        The audit's files (:func:`stereovar.audit.layout.discover`).

    Raises
    ------
    ImageError
        One line naming the first such file, what it is and the fix.
    """
    for frame in discovery.frames:
        for path in frame.files():
            regular_file(path)
            if not os.access(path, os.R_OK):
                raise ImageError(
                    f"{path}: this user may not read it; make it readable (chmod u+r {path}) "
                    "or run as its owner"
                )


def check_headers(discovery: Discovery) -> None:
    """Every file of the audit read as far as its header, no pixel decoded: each frame's
    images' sizes (:func:`~stereovar.audit.decoding.check_sizes`: a header that cannot be
    read, as a truncated HDF5 file's, sizes that differ, an Infinigen depth without its
    camview files) and its camera files (:func:`~stereovar.audit.generators.read_camera`).
    ``stereovar audit`` calls it before Snakemake starts, so such a file stops the audit
    before any import job.

    Parameters
    ----------
    discovery : Discovery
        The audit's files (:func:`stereovar.audit.layout.discover`).

    Raises
    ------
    AuditError, ImageError
        One line naming the first such file and the fix.
    """
    from .decoding import check_sizes
    from .generators import read_camera

    for frame in discovery.frames:
        check_sizes(frame)
        for path in frame.cameras.values():
            read_camera(path)


def frame_files(discovery: Discovery, frame: str) -> list[str]:
    """Every file one frame is imported from (renders of each view and seed, then its
    ground truth): the inputs of its ``audit_import`` job."""
    return [str(p) for f in discovery.frames if f.name == frame for p in f.files()]


def import_params(settings: dict) -> str:
    """The ``settings`` param of every ``audit_import`` job.

    Reordering the ``audit:`` keys or writing a default out (``scale: 1.0``,
    ``channels: {}``) reruns nothing, and settings the import does not read
    (``mitigations``, ``probe``) do not import the frames again. The files' templates are
    the job's inputs; the job reads the settings from the workflow's config.

    Parameters
    ----------
    settings : dict
        The ``audit:`` section of the config.

    Returns
    -------
    str
        The digest of the settings as the import applies them
        (:func:`~stereovar.audit.settings.settings_digest`).
    """
    return settings_digest(settings)


def import_fingerprint(settings: dict, discovery: Discovery, frame: str) -> str:
    """The ``params`` of one frame's ``audit_import`` job that changes when a file is
    replaced keeping its size and mtime, not when it is only touched
    (:func:`~stereovar.audit.hashing.frame_fingerprint`)."""
    return frame_fingerprint(settings, next(f for f in discovery.frames if f.name == frame))


def frame_pattern(discovery: Discovery) -> str:
    """A regular expression matching exactly the audit's frame names (the ``{scene}``
    wildcard constraint of ``audit_import``)."""
    return "|".join(re.escape(f.name) for f in discovery.frames)


def import_outputs(settings: dict, n_seeds: int, frame: str = "{scene}") -> dict:
    """The outputs of one frame's import (``frame`` may be a wildcard): each view's render
    store and the ground-truth store (:func:`~stereovar.audit.settings.frame_stores`), and
    ``record``, the frame's :func:`~stereovar.layout.import_record`."""
    settings = {**settings, **import_settings(settings)}
    return {
        **frame_stores(settings, frame, n_seeds),
        "record": import_record(settings["name"], frame),
    }


def audit_run_config(config: dict, discovery: Discovery) -> dict:
    """The config keys an audit replaces: ``scenes`` (its frames), ``resolution``, the rig's
    convention, and ``render`` (source ``audit/{name}``, the seeds estimator, N and SPP
    from the files, one store per view and frame, no render cache); the intervention uses
    all N seeds."""
    settings = config["audit"]
    frames = [f.name for f in discovery.frames]
    n, spp = discovery.n_seeds, audit_spp(settings)
    height, width = image_size(next(iter(discovery.frames[0].renders[VIEWS[0]].values())))
    return {
        "scenes": frames,
        "resolution": {"width": width, "height": height},
        "rig": {**config["rig"], "convention": settings.get("convention") or "conventional"},
        "render": {
            **config["render"],
            "renderer": audit_source(settings["name"]),
            "estimator": "seeds",
            "n_seeds": n,
            "seeds_per_job": n,
            "spp": spp,
            "spp_sweep": {"scene": frames[0], "spp": [spp]},
            "cache": None,
        },
        "intervention": {**config["intervention"], "n_seeds": None, "spp": None},
    }


def check_audit_memory(config: dict, discovery: Discovery, limit_mb: int, source: str) -> None:
    """Refuse an audit whose renders are too large for the memory one job may use.

    Parameters
    ----------
    config : dict
        The run's config with the audit's keys (:func:`audit_run_config`).
    discovery : Discovery
        The audit's files (:func:`discover_audit`).
    limit_mb, source
        The most memory one job may request and where that bound comes from
        (:func:`stereovar.resources.memory_limit`).

    Raises
    ------
    AuditError
        One line: the renders' size (and one of them), the job and its request, the bound,
        and the largest size of the same aspect ratio that fits, or, when none does, how
        to raise the bound (:func:`stereovar.resources.memory_excess`).
    """
    excess = sizing.memory_excess(config, limit_mb)
    if excess is None:
        return
    width, height = config["resolution"]["width"], config["resolution"]["height"]
    example = next(iter(discovery.frames[0].renders[VIEWS[0]].values()))
    if excess.fitting is None:
        fix = f"no image size fits; {sizing.raise_bound(source, excess.smallest)}"
    else:
        fix = f"crop or downsample the renders to at most {excess.fitting[0]}x{excess.fitting[1]}"
        if source == sizing.MACHINE:
            fix += ", or audit them on a machine with more memory (on a cluster, set "
            fix += "cluster.max_mem_mb to the memory of its largest node)"
    raise AuditError(
        f"audit.renders: the renders are {width}x{height} pixels ({example}), so each "
        f"{excess.job} job would request {excess.request:,} MB of memory, more than the "
        f"{limit_mb:,} MB of {source}; {fix}"
    )


def check_audit_run(config: dict, discovery: Discovery, *, global_mem_mb=None) -> None:
    """The workflow's checks of an audit's run config, made by ``stereovar audit`` before
    Snakemake starts: every ``audit.mitigations`` entry is a store transform
    (:func:`stereovar.mitigations.audit_mitigation_runs`) and the largest job fits in
    memory (:func:`check_audit_memory`, :func:`stereovar.resources.memory_limit`).

    Parameters
    ----------
    config : dict
        The validated workflow config with the audit's keys (:func:`audit_run_config`).
    discovery : Discovery
        The audit's files.
    global_mem_mb : int, optional
        The run's ``--resources mem_mb``.

    Raises
    ------
    ConfigError, AuditError
        One line naming the setting and the fix.
    """
    from ..mitigations import audit_mitigation_runs

    if config["audit"].get("mitigations"):
        audit_mitigation_runs(config)
    limit = sizing.memory_limit(config, global_mem_mb=global_mem_mb)
    check_audit_memory(config, discovery, *limit)


PREVIOUS = "previous"
"""Folder of an audit's results that holds the verdict a run set aside
(:func:`set_aside_verdict`)."""


def set_aside_verdict(name: str, root=".") -> list[Path]:
    """Move an audit's verdict page and summary (:func:`audit_paths`) under ``root`` into
    ``results/audit/<name>/previous/``, replacing what an earlier run set aside there.

    A run that imports a frame again or rebuilds the verdict calls it before its first job
    (``onstart``): until the verdict job has written the new page, no page claims a verdict
    on stores that are being replaced, whether the run then succeeds, fails or is killed.
    Each file is moved with one rename (nothing is copied or lost).

    Parameters
    ----------
    name : str
        The audit's ``audit.name``.
    root : path-like, optional
        The folder the run works in (default: the current one).

    Returns
    -------
    list of Path
        The files set aside, at their new paths.
    """
    paths = audit_paths(name)
    moved = []
    for key in ("verdict_md", "verdict_html", "summary"):
        path = Path(root) / paths[key]
        if not path.is_file():
            continue
        target = path.parent / PREVIOUS / path.name
        target.parent.mkdir(exist_ok=True)
        os.replace(path, target)
        moved.append(target)
    return moved


def audit_paths(name: str) -> dict:
    """The verdict page, its summary and the per-frame teaser pattern of an audit."""
    return {
        "verdict_md": layout.audit_verdict(name, "md"),
        "verdict_html": layout.audit_verdict(name, "html"),
        "summary": layout.audit_summary(name),
        "teaser": layout.audit_teaser(name, "{scene}"),
    }


def audit_targets(config: dict) -> list[str]:
    """What ``all`` builds for an audit: the imported ground truth and import records, every
    frame's correlation rows and intervention, the pooled tables and figures, one teaser per frame,
    and the verdict page with its summary."""
    source = config["render"]["renderer"]
    spp = config["render"]["spp"]
    frames = list(config["scenes"])
    paths = audit_paths(config["audit"]["name"])
    tables = ["statistics", "seed_curve", "cross_scene", "intervention"]
    return [
        *[ground_truth_store(source, f) for f in frames],
        *[import_record(config["audit"]["name"], f) for f in frames],
        *[layout.correlation_rows(source, "seeds", f, spp) for f in frames],
        *[layout.intervention_metrics(source, "seeds", f) for f in frames],
        *[p for t in tables for p in layout.run_tables(source, "seeds", t)],
        layout.run_figure(source, "seeds", "statistics_dots"),
        layout.run_figure(source, "seeds", "rho_vs_seeds"),
        *[paths["teaser"].format(scene=f) for f in frames],
        paths["verdict_md"],
        paths["verdict_html"],
        paths["summary"],
    ]
