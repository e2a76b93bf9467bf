"""Where the documentation lives: the one place pages, configs and messages take a docs
address from, so that nothing a user reads points at a path of the source repository.

The base is the ``Documentation`` address of the installed package's metadata
(``[project.urls]`` in ``pyproject.toml``); ``STEREOVAR_DOCS_URL`` overrides it, for a site
built and served elsewhere (``make docs`` writes one under ``docs/_build/html``).
"""

from __future__ import annotations

import os

#: The published documentation, as ``pyproject.toml`` names it (``.readthedocs.yaml`` builds it).
DEFAULT_DOCS_URL = "https://stereovar.readthedocs.io/en/latest/"


def docs_base() -> str:
    """The documentation's base address, ending in ``/``.

    Examples
    --------
    >>> docs_base().endswith("/")
    True
    """
    base = os.environ.get("STEREOVAR_DOCS_URL", "").strip()
    if not base:
        base = _metadata_url() or DEFAULT_DOCS_URL
    return base if base.endswith("/") else base + "/"


def _metadata_url() -> str | None:
    """The ``Documentation`` project URL of the installed distribution, if any."""
    from importlib import metadata

    try:
        urls = metadata.metadata("stereovar").get_all("Project-URL") or []
    except metadata.PackageNotFoundError:
        return None
    for entry in urls:
        label, _, url = entry.partition(",")
        if label.strip().lower() == "documentation" and url.strip():
            return url.strip()
    return None


def docs_page(page: str, anchor: str | None = None) -> str:
    """The address of one documentation page, by its source name without suffix.

    Parameters
    ----------
    page : str
        The page's name in ``docs/`` without ``.md``/``.rst``, e.g. ``"audit"`` or
        ``"configuration"``; ``""`` for the front page.
    anchor : str, optional
        A section anchor on that page (MyST's heading slug).

    Examples
    --------
    >>> import os
    >>> os.environ["STEREOVAR_DOCS_URL"] = "https://example.org/docs"
    >>> docs_page("audit", "the-verdict")
    'https://example.org/docs/audit.html#the-verdict'
    >>> docs_page("")
    'https://example.org/docs/'
    >>> del os.environ["STEREOVAR_DOCS_URL"]
    """
    url = docs_base() + (f"{page}.html" if page else "")
    return f"{url}#{anchor}" if anchor else url
