"""What a shared page or summary says about where it came from: the stereovar version that
wrote it, when, and a hash of its inputs and of its config.

A verdict page or ``summary.json`` travels: a data team mails it, attaches it to a ticket or
archives it beside the data set. :func:`provenance` gives the three facts that let a reader
tie it back to what was measured: ``stereovar_version``, ``created`` (UTC, to the second),
``inputs_sha256`` (one SHA-256 over the inputs' own SHA-256s, in path order, so it changes
exactly when an input's bytes or the set of inputs change) and ``config_sha256`` (the
config's digest, :func:`stereovar.io.contracts.config_digest`). :func:`provenance_line`
words them for the pages.
"""

from __future__ import annotations

import hashlib
from datetime import datetime, timezone

__all__ = ["file_hashes", "inputs_digest", "provenance", "provenance_line"]


def inputs_digest(hashes: dict) -> str:
    """One SHA-256 over inputs' SHA-256s: the lines ``path<TAB>sha256`` in path order.

    .. math::

        h = \\operatorname{SHA256}\\Bigl(\\textstyle\\bigoplus_{p \\in \\operatorname{sort}(P)}
            p \\,\\|\\, \\mathtt{TAB} \\,\\|\\, h_p \\,\\|\\, \\mathtt{LF}\\Bigr)

    Parameters
    ----------
    hashes : dict
        Each input's path (as the config names it) to its SHA-256 (hex).

    Returns
    -------
    str
        The hex digest; that of no lines when ``hashes`` is empty.

    Examples
    --------
    >>> a = inputs_digest({"b.exr": "22", "a.exr": "11"})
    >>> a == inputs_digest({"a.exr": "11", "b.exr": "22"})
    True
    >>> a == inputs_digest({"a.exr": "11", "b.exr": "23"})
    False
    """
    text = "".join(f"{path}\t{digest}\n" for path, digest in sorted(hashes.items()))
    return hashlib.sha256(text.encode()).hexdigest()


def file_hashes(paths) -> dict:
    """Each file's SHA-256 (hex) by its path as given."""
    out = {}
    for path in paths:
        with open(path, "rb") as f:
            out[str(path)] = hashlib.file_digest(f, "sha256").hexdigest()
    return out


def provenance(hashes: dict, config_sha256: str, *, now: datetime | None = None) -> dict:
    """The provenance block of a page or summary.

    Parameters
    ----------
    hashes : dict
        Each input's path to its SHA-256 (:func:`inputs_digest`).
    config_sha256 : str
        The config's digest (:func:`stereovar.io.contracts.config_digest`).
    now : datetime, optional
        The time to record (default: now, UTC).

    Returns
    -------
    dict
        ``stereovar_version``, ``created`` (ISO 8601, UTC, seconds), ``inputs_sha256``,
        ``n_inputs`` and ``config_sha256``.

    Examples
    --------
    >>> from datetime import datetime, timezone
    >>> p = provenance({"a.exr": "11"}, "c0ffee",
    ...                now=datetime(2026, 1, 2, 3, 4, 5, tzinfo=timezone.utc))
    >>> p["created"], p["n_inputs"], p["config_sha256"]
    ('2026-01-02T03:04:05Z', 1, 'c0ffee')
    """
    from . import __version__

    when = (now or datetime.now(timezone.utc)).astimezone(timezone.utc)
    return {
        "stereovar_version": __version__,
        "created": when.strftime("%Y-%m-%dT%H:%M:%SZ"),
        "inputs_sha256": inputs_digest(hashes),
        "n_inputs": len(hashes),
        "config_sha256": str(config_sha256 or ""),
    }


def provenance_line(p: dict) -> str:
    """:func:`provenance` as one line for a page's foot or head.

    Examples
    --------
    >>> provenance_line({"stereovar_version": "0.1.0", "created": "2026-01-02T03:04:05Z",
    ...                  "inputs_sha256": "ab" * 32, "n_inputs": 3, "config_sha256": "cd" * 32})
    ... # doctest: +NORMALIZE_WHITESPACE
    'stereovar 0.1.0 · 2026-01-02 03:04:05 UTC · 3 input files, SHA-256 abababababab… ·
     config SHA-256 cdcdcdcdcdcd…'
    """
    if not p:
        return ""
    created = str(p.get("created", "")).replace("T", " ").replace("Z", " UTC")
    return (
        f"stereovar {p.get('stereovar_version', '?')} · {created} · "
        f"{p.get('n_inputs', 0)} input files, SHA-256 {str(p.get('inputs_sha256', ''))[:12]}… · "
        f"config SHA-256 {str(p.get('config_sha256', ''))[:12]}…"
    )
