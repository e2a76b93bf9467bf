"""The ``audit:`` settings as an import applies them: checked before any file is read
(:func:`check_settings`, :func:`check_paths`), their defaults filled in
(:func:`import_settings`) and digested (:func:`settings_digest`: a change re-imports), and
the stores a frame is imported to (:func:`frame_stores`).

The audit's files themselves are found by :mod:`stereovar.audit.layout`; the import that
reads them is :mod:`stereovar.audit.importer`.
"""

from __future__ import annotations

import re

from ..errors import AuditError
from ..experiment import audit_source, batch_label, ground_truth_store, render_store
from ..io.channels import ROLES
from ..io.contracts import config_digest
from ..rig import VIEWS
from .ground_truth import CONVENTIONS
from .layout import NAME

IMPORT_KEYS = (
    "views",
    "convention",
    "transfer",
    "scale",
    "disparity_scale",
    "focal_px",
    "baseline_m",
    "glass_ids",
    "spp",
    "sign_check",
    "channels",
)
"""``audit:`` settings that change what a frame imports to (a change re-imports it)."""

RELATIONS = {1: "x_R = x_L + d", -1: "x_R = x_L - d"}
"""The correspondence of each disparity sign :math:`s`
(:data:`~stereovar.audit.ground_truth.CONVENTIONS`), as the import's lines write it."""

DEFAULT_DISPARITY_SCALE = 256.0
"""PNG disparity is value / 256 (KITTI); 0 is invalid."""


def audit_spp(settings: dict) -> int:
    """The SPP the audit's stores are labelled with: ``audit.spp``, or 0 (not given)."""
    return int(settings.get("spp") or 0)


def frame_stores(settings: dict, frame: str, n_seeds: int) -> dict:
    """View (and ``ground_truth``) to the store paths of one imported frame."""
    source = audit_source(settings["name"])
    batch = batch_label(range(n_seeds))
    stores = {
        view: render_store(source, frame, view, audit_spp(settings), batch) for view in VIEWS
    }
    stores["ground_truth"] = ground_truth_store(source, frame)
    return stores


def _number(settings: dict, key: str, default):
    value = settings.get(key)
    if value is None:
        return default
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise AuditError(f"audit.{key} is {value!r}, not a number; give a number or leave it out")
    return float(value)


def import_settings(settings: dict) -> dict:
    """The ``audit:`` settings of :data:`IMPORT_KEYS` as the import applies them.

    Each one not given takes the value the import uses for it (the schema's default:
    ``convention: conventional``, ``scale: 1``, ``disparity_scale: 256``, ``glass_ids: []``,
    ``spp: 0``, ``sign_check: stop``, ``channels: {}``); numbers are floats (``scale: 1``
    and ``scale: 1.0`` are one import). The settings as written and the same settings with
    the schema's defaults filled in (the workflow's) so give one :func:`settings_digest`.

    Parameters
    ----------
    settings : dict
        The ``audit:`` config section.

    Returns
    -------
    dict
        :data:`IMPORT_KEYS` to their values.

    Raises
    ------
    AuditError
        A number that is not one, or an ``audit.channels`` entry that is not a role and a
        channel name (one line).
    """
    views = settings.get("views") or {}
    focal, baseline = _number(settings, "focal_px", None), _number(settings, "baseline_m", None)
    return {
        "views": {v: str(views.get(v, v)) for v in VIEWS},
        "convention": settings.get("convention") or "conventional",
        "transfer": settings.get("transfer") or None,
        "scale": _number(settings, "scale", 1.0),
        "disparity_scale": _number(settings, "disparity_scale", DEFAULT_DISPARITY_SCALE),
        "focal_px": focal or None,
        "baseline_m": baseline or None,
        "glass_ids": [int(i) for i in settings.get("glass_ids") or []],
        "spp": audit_spp(settings),
        "sign_check": settings.get("sign_check") or "stop",
        "channels": _channels(settings),
    }


def _channels(settings: dict) -> dict:
    """``audit.channels``, checked: role (:data:`~stereovar.io.channels.ROLES`) to the
    EXR channel (for ``render``, the layer) that holds it."""
    given = settings.get("channels") or {}
    if not isinstance(given, dict):
        raise AuditError(
            f"audit.channels is {given!r}; give a mapping of role to channel name, e.g. "
            "{depth: ViewLayer.Depth.Z}"
        )
    for role, name in given.items():
        if role not in ROLES:
            raise AuditError(
                f"audit.channels has the unknown role {role!r}; use {', '.join(ROLES)}"
            )
        if not isinstance(name, str) or not name:
            raise AuditError(
                f"audit.channels.{role} is {name!r}, not a channel name; give the EXR "
                "channel's name (e.g. ViewLayer.Depth.Z) or leave it out"
            )
    return {role: given[role] for role in ROLES if role in given}


def settings_digest(settings: dict) -> str:
    """SHA-256 of the :func:`import_settings` of ``settings`` (a change re-imports)."""
    return config_digest(import_settings(settings))



PATH_KEYS = ("root", "renders", "disparity", "depth", "glass_mask", "segmentation")
"""``audit:`` settings that are paths (or path templates) of the audit's files."""

PATH_VARIABLE = re.compile(r"<[a-z][a-z0-9_]*>")
"""What Snakemake (9.x) reads as a path variable in an input or output path: ``<word>``,
replaced by its folder (``<results>``, ``<resources>``, ...) or an error when unknown."""


def check_paths(settings: dict) -> None:
    """Refuse an audit path that holds a Snakemake path variable (:data:`PATH_VARIABLE`).

    The audit's files are the inputs of its ``audit_import`` jobs: Snakemake stops on an
    unknown ``<b>`` in them (``UndefinedPathvarException``) and silently puts its own folder
    in place of a known one (``<results>``).

    Parameters
    ----------
    settings : dict
        The ``audit:`` config section: :data:`PATH_KEYS` and the ``views`` values, which
        become parts of the render and ground-truth paths.

    Raises
    ------
    AuditError
        One line naming the key, the path variable and the fix.

    Examples
    --------
    >>> check_paths({"renders": "data/{frame}/{view}/seed_{seed}.exr"})
    >>> check_paths({"renders": "data/<results>/{view}/{seed}.exr"})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    stereovar.errors.AuditError: audit.renders 'data/<results>/{view}/{seed}.exr' holds ...
    """
    views = settings.get("views") or {}
    given = [(key, settings.get(key)) for key in PATH_KEYS]
    given += [(f"views.{view}", views.get(view)) for view in VIEWS]
    for key, value in given:
        match = PATH_VARIABLE.search(str(value)) if value is not None else None
        if match:
            raise AuditError(
                f"audit.{key} {value!r} holds {match.group()}, which Snakemake reads as a "
                "path variable (an unknown one stops the workflow, a known one such as "
                "<results> is replaced by its folder); rename the folder or file so that "
                f"no <word> is in the path, and set audit.{key} to the new path"
            )


def check_settings(settings: dict) -> None:
    """The ``audit:`` settings that need no file: the name, the convention and the paths
    (:func:`check_paths`)."""
    check_paths(settings)
    name = str(settings.get("name") or "")
    if not NAME.fullmatch(name):
        raise AuditError(
            f"audit.name {name!r} may only contain letters, digits, _ and - (it names "
            "results/audit/<name>/); pick another name"
        )
    convention = settings.get("convention") or "conventional"
    if convention not in CONVENTIONS:
        raise AuditError(
            f"audit.convention {convention!r} is unknown; use "
            + " or ".join(f"{name} ({RELATIONS[s]})" for name, s in CONVENTIONS.items())
        )


