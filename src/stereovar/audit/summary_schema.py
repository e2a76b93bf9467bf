"""The versioned schema of an audit's ``summary.json``, checked on every write.

``results/audit/{name}/summary.json`` is what a team's scripts and CI read (``stereovar audit
--fail-on`` reads its ``light`` and its ``summary[0]`` line). Its JSON Schema ships in the
package (``stereovar/schemas/audit_summary.schema.json``, :data:`SCHEMA_PATH`); the
verdict job validates each summary against it before writing (:func:`validate_summary`), so a
file that exists has the documented keys and types. The docs page ``summary_json`` describes
each key.

Versioning: ``schema_version`` is ``major.minor``. A minor version only adds keys; removing a
key or changing its meaning makes a new major version, so a script written for ``1.x`` reads
any ``1.y``. Version 1.1 adds ``mc_specific_rho`` (the verdict's number with its interval,
its null and the light) and ``provenance`` (:mod:`stereovar.provenance`). A summary of
another major version is refused by :func:`read_summary` with the version it has and the
one this stereovar reads, before its keys are checked.
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

SUMMARY_SCHEMA_VERSION = "1.1"
"""The version the verdict job writes."""

SCHEMA_PATH = Path(__file__).resolve().parents[1] / "schemas" / "audit_summary.schema.json"
"""The JSON Schema (draft 2020-12) of ``summary.json``."""


@cache
def summary_schema() -> dict:
    """The JSON Schema of ``summary.json`` (:data:`SCHEMA_PATH`), parsed."""
    return json.loads(SCHEMA_PATH.read_text())


def validate_summary(summary: dict) -> None:
    """Check an audit summary against :func:`summary_schema`.

    Raises
    ------
    ValueError
        The summary breaks the schema: one line naming the key and what is wrong.

    Examples
    --------
    >>> validate_summary({"schema_version": "1.1"})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: summary.json breaks its schema ... at (top level): 'audit' is a required ...
    """
    import jsonschema

    validator = jsonschema.Draft202012Validator(summary_schema())
    errors = sorted(validator.iter_errors(summary), key=lambda e: list(e.absolute_path))
    if errors:
        e = errors[0]
        where = "/".join(map(str, e.absolute_path)) or "(top level)"
        raise ValueError(
            f"summary.json breaks its schema ({SCHEMA_PATH.name}) at {where}: {e.message}"
        )


def _version() -> str:
    from .. import __version__

    return __version__


def read_summary(path) -> dict:
    """An audit's ``summary.json``, read through :func:`summary_schema`: what ``stereovar
    audit`` prints and its ``--fail-on`` gate decides from. A file that is not JSON, not a
    JSON object, has another major schema version or breaks the schema is refused, so that
    the gate fails closed on a verdict it cannot read rather than pass on a ``light`` it was
    handed.

    Parameters
    ----------
    path : path-like
        ``results/audit/{name}/summary.json``.

    Returns
    -------
    dict

    Raises
    ------
    AuditError
        One line: the file, what is wrong with it, and to remove it and run the audit again
        (the verdict job writes it anew).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "summary.json"
    >>> _ = path.write_text('{"light": "green", "summary": "GREEN"}')
    >>> read_summary(path)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    stereovar.errors.AuditError: .../summary.json is not a summary the verdict job wrote: ...
    """
    from ..errors import AuditError

    fix = "remove it and run the same stereovar audit command again to write it anew"
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise AuditError(
            f"{path}: cannot read the audit's summary ({getattr(err, 'strerror', None) or err});"
            f" {fix}"
        ) from None
    try:
        summary = json.loads(text)
    except ValueError as err:
        raise AuditError(
            f"{path} is not a summary the verdict job wrote: it is not JSON ({err}); {fix}"
        ) from None
    if not isinstance(summary, dict):
        raise AuditError(
            f"{path} is not a summary the verdict job wrote: it holds a JSON "
            f"{type(summary).__name__}, not an object; {fix}"
        )
    version = str(summary.get("schema_version", ""))
    major = SUMMARY_SCHEMA_VERSION.split(".")[0]
    if version and version.split(".")[0] != major:
        raise AuditError(
            f"{path} has summary schema version {version}; this stereovar "
            f"{_version()} reads {major}.x: read it with the stereovar that wrote it, or "
            f"{fix}"
        )
    try:
        validate_summary(summary)
    except ValueError as err:
        raise AuditError(f"{path} is not a summary the verdict job wrote: {err}; {fix}") from None
    return summary
