"""Every result path of a run, keyed by (source, transform, estimator).

A run is **source → transform → estimator → analysis** (``DESIGN.md``). Its results sit
under one directory per source and transform, the *source key*:

``results/{source}``
    the source's own renders (``transform`` :data:`NONE`: the segment is left out, so the
    paths of runs without mitigations never changed);
``results/{source}/{transform}``
    the same scenes after a mitigation: a store transform (:mod:`stereovar.transforms`)
    applied to the source's renders, or a render-time policy (``shared_seed``) that renders
    them anew.

``source`` is a renderer (``mitsuba``, ``cycles``) or an audit (``audit/{name}``). Under a
source key:

``renders/{scene}/{view}/spp{spp}/seeds{first}-{last}.zarr``
    one batch of renders of one view (:mod:`stereovar.io.renders`);
``renders/{scene}/{view}/spp{spp}/moments.zarr``
    one view's sample moments (:mod:`stereovar.io.moments`);
``renders/{scene}/{view}/aux.zarr``
    one view's auxiliary passes (albedo and normal) for the denoiser (source keys without a
    transform only);
``{estimator}/...``
    everything computed from those renders by one estimator: ``variance``, ``warped``,
    ``correlation``, ``intervention``, ``mitigation``, ``tables``, ``figures``.

Ground truth belongs to the scene, not to a transform: ``results/ground_truth/{scene}.zarr``
(traced for every renderer) or ``results/audit/{name}/ground_truth/{frame}.zarr`` (imported).
Tables across runs sit under ``results/tables/`` and figures across runs under
``results/figures/``.

The workflow's rules match the source key with one ``{renderer}`` wildcard
(:func:`source_key_pattern`), so every rule from the variance estimator to the tables runs
unchanged on transformed renders.

Importing this module pulls in no third-party package.
"""

from __future__ import annotations

import re

__all__ = [
    "AUDIT_PREFIX",
    "NONE",
    "RESULTS",
    "audit_source",
    "aux_store",
    "ground_truth_store",
    "is_audit",
    "mitigation_figure",
    "mitigation_rows",
    "mitigation_tables",
    "moment_store",
    "render_store",
    "run_prefix",
    "source_key",
    "source_key_pattern",
    "split_source_key",
    "table_paths",
]

RESULTS = "results"
"""The directory every result path starts with."""

NONE = "none"
"""The identity transform: the source's own renders, with no path segment."""

AUDIT_PREFIX = "audit/"
"""Source names of audits: ``audit/{name}``."""

TABLE_FORMATS = ("csv", "md", "tex", "html")
"""The formats every table is written in."""


def audit_source(name: str) -> str:
    """The source name of the audit ``name``: ``audit/{name}``."""
    return f"{AUDIT_PREFIX}{name}"


def is_audit(source: str) -> bool:
    """Whether a source (or source key) is an audit's (:func:`audit_source`)."""
    return str(source).startswith(AUDIT_PREFIX)


def source_key(source: str, transform: str = NONE) -> str:
    """The directory name of a source's renders after ``transform``, under ``results/``.

    Examples
    --------
    >>> source_key("mitsuba")
    'mitsuba'
    >>> source_key("mitsuba", "denoise")
    'mitsuba/denoise'
    >>> source_key("audit/team", "equalise")
    'audit/team/equalise'
    """
    transform = transform or NONE
    if "/" in transform or not transform:
        raise ValueError(f"a transform name has no '/', got {transform!r}")
    return str(source) if transform == NONE else f"{source}/{transform}"


def split_source_key(key: str) -> tuple[str, str]:
    """``(source, transform)`` of a source key (inverse of :func:`source_key`).

    Examples
    --------
    >>> split_source_key("mitsuba/denoise")
    ('mitsuba', 'denoise')
    >>> split_source_key("audit/team")
    ('audit/team', 'none')
    >>> split_source_key("audit/team/sensor_only")
    ('audit/team', 'sensor_only')
    """
    parts = str(key).split("/")
    n_source = 2 if is_audit(key) else 1
    if len(parts) not in (n_source, n_source + 1):
        raise ValueError(f"not a source key: {key!r}")
    source = "/".join(parts[:n_source])
    return source, parts[n_source] if len(parts) > n_source else NONE


def source_key_pattern(renderers, transforms) -> str:
    """The regular expression of a source key: a renderer or ``audit/{name}``, optionally
    followed by ``/{transform}`` (one of ``transforms``, never :data:`NONE`)."""
    source = "|".join(
        [*(re.escape(r) for r in renderers), re.escape(AUDIT_PREFIX) + r"[A-Za-z0-9_-]+"]
    )
    names = [re.escape(t) for t in transforms if t != NONE]
    suffix = f"(?:/(?:{'|'.join(names)}))?" if names else ""
    return f"(?:{source}){suffix}"


def render_store(source: str, scene: str, view: str, spp, batch, transform: str = NONE) -> str:
    """One batch of renders:
    ``results/{source}[/{transform}]/renders/{scene}/{view}/spp{spp}/seeds{batch}.zarr``."""
    key = source_key(source, transform)
    return f"{RESULTS}/{key}/renders/{scene}/{view}/spp{spp}/seeds{batch}.zarr"


def moment_store(source: str, scene: str, view: str, spp, transform: str = NONE) -> str:
    """One view's moment store:
    ``results/{source}[/{transform}]/renders/{scene}/{view}/spp{spp}/moments.zarr``."""
    key = source_key(source, transform)
    return f"{RESULTS}/{key}/renders/{scene}/{view}/spp{spp}/moments.zarr"


def aux_store(source: str, scene: str, view: str) -> str:
    """One view's auxiliary passes (albedo, normal) for the denoiser:
    ``results/{source}/renders/{scene}/{view}/aux.zarr``."""
    return f"{RESULTS}/{source}/renders/{scene}/{view}/aux.zarr"


def ground_truth_store(source: str, scene: str) -> str:
    """A scene's ground truth: ``results/ground_truth/{scene}.zarr``, traced from the scene
    for every renderer and transform, or ``results/audit/{name}/ground_truth/{frame}.zarr``,
    imported with an audit's renders. ``source`` may be a source key."""
    source, _ = split_source_key(source)
    if is_audit(source):
        return f"{RESULTS}/{source}/ground_truth/{scene}.zarr"
    return f"{RESULTS}/ground_truth/{scene}.zarr"


def run_prefix(source: str, estimator: str, transform: str = NONE) -> str:
    """Directory of everything computed from one source's renders after ``transform`` by
    one estimator: ``results/{source}[/{transform}]/{estimator}``."""
    return f"{RESULTS}/{source_key(source, transform)}/{estimator}"


def mitigation_rows(source: str, estimator: str, scene: str, spp, transform: str = NONE) -> str:
    """One scene's mitigation measurements (residual correlations and image quality):
    ``results/{source}[/{transform}]/{estimator}/mitigation/{scene}/spp{spp}.csv``."""
    return f"{run_prefix(source, estimator, transform)}/mitigation/{scene}/spp{spp}.csv"


def table_paths(name: str, prefix: str = f"{RESULTS}/tables") -> list[str]:
    """A table in every :data:`TABLE_FORMATS`: ``{prefix}/{name}.{ext}``."""
    return [f"{prefix}/{name}.{ext}" for ext in TABLE_FORMATS]


def mitigation_figure(source: str | None = None) -> str:
    """The mitigation trade-off figure: ``results/figures/mitigations.png``, or
    ``results/audit/{name}/figures/mitigations.png`` for an audit."""
    if source is not None and is_audit(source):
        return f"{RESULTS}/{source}/figures/mitigations.png"
    return f"{RESULTS}/figures/mitigations.png"


def mitigation_tables(source: str | None = None) -> list[str]:
    """The mitigation table: ``results/tables/mitigations.*`` for the run's renderer, or
    ``results/audit/{name}/tables/mitigations.*`` for an audit."""
    if source is not None and is_audit(source):
        return table_paths("mitigations", f"{RESULTS}/{source}/tables")
    return table_paths("mitigations")
