"""The blocks every self-contained page shares: the document, a table, a figure, a link.

A page is one HTML file with its own stylesheet (``base.html.j2``'s shared rules plus the
page's), no script and nothing loaded from a server: figures are PNG files beside it (a
relative path) or embedded in it (:func:`data_uri`), links are relative to the page's folder
(:func:`relative_link`). :func:`document`, :func:`table` and :func:`figure` render the
templates of :mod:`stereovar.pages.templates` for a page that still passes ready fragments;
a new page extends ``base.html.j2`` and imports ``macros.html.j2`` itself.
"""

from __future__ import annotations

import base64
import os
from pathlib import Path

__all__ = ["data_uri", "document", "figure", "relative_link", "table"]

_MIME = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".svg": "image/svg+xml"}


def _macros():
    """The module of ``macros.html.j2`` (its macros as functions)."""
    from .templates import environment

    return environment().get_template("macros.html.j2").module


def document(title: str, body: list[str], css: str = "") -> str:
    """One self-contained HTML document (``document.html.j2``, extending ``base.html.j2``).

    Parameters
    ----------
    title : str
        The page's ``<title>`` (escaped here).
    body : list of str
        The body's HTML fragments, in order, one per line (already HTML: they are printed
        as they are).
    css : str, optional
        The page's own stylesheet, after the shared one (``base.html.j2``).

    Returns
    -------
    str
        The document, starting with ``<!DOCTYPE html>`` and ending in a newline.

    Examples
    --------
    >>> page = document("A & B", ["<p>hi</p>"], css="p { color: red; }")
    >>> page.startswith("<!DOCTYPE html>"), "<title>A &amp; B</title>" in page
    (True, True)
    >>> page.index("p { color: red; }") < page.index("</style>") < page.index("<p>hi</p>")
    True
    """
    from markupsafe import Markup

    from .templates import render

    return render(
        "document.html.j2", title=title, css=Markup(css), body=[Markup(b) for b in body if b]
    )


def table(rows: list[dict], columns: list[str], caption: str = "", digits: int = 4) -> str:
    """A ``<table>`` (the ``table`` macro of ``macros.html.j2``): numbers to ``digits``
    significant digits and right-aligned, headers, cells and caption escaped.

    Examples
    --------
    >>> t = table([{"a": 1.23456, "b": "<x>"}], ["a", "b"], digits=3)
    >>> t.startswith("<table") and "1.23" in t and "&lt;x&gt;" in t
    True
    """
    return str(_macros().table(rows, columns, caption=caption, digits=digits))


def figure(src: str, caption_html: str, *, alt: str, ident: str = "") -> str:
    """A ``<figure>`` of one image with its caption (the ``figure`` macro).

    Parameters
    ----------
    src : str
        The image: a path relative to the page, or a data URI (:func:`data_uri`); escaped
        here.
    caption_html : str
        The ``<figcaption>``'s content, already HTML (escape plain text first).
    alt : str
        The image's text alternative (escaped here).
    ident : str, optional
        The figure's ``id``, so a page can link to it.

    Examples
    --------
    >>> print(figure("figures/a&b.png", "Fig. 1", alt="a", ident="fig-a"))
    ... # doctest: +NORMALIZE_WHITESPACE
    <figure id="fig-a"><img src="figures/a&amp;b.png"
    alt="a"><figcaption>Fig. 1</figcaption></figure>
    """
    from markupsafe import Markup

    return str(_macros().figure(src, Markup(caption_html), alt, ident))


def data_uri(path) -> str:
    """An image file as a ``data:`` URI (base64), so a page shows it without the file.

    Raises
    ------
    ValueError
        The file is not a PNG, JPEG or SVG image (by its suffix).
    """
    path = Path(path)
    mime = _MIME.get(path.suffix.lower())
    if mime is None:
        raise ValueError(f"cannot embed {path}: not one of {', '.join(sorted(_MIME))}")
    return f"data:{mime};base64,{base64.b64encode(path.read_bytes()).decode('ascii')}"


def relative_link(path, page) -> str:
    """``path`` as a link from the page ``page`` (both relative to one folder, or both
    absolute), with ``/`` separators.

    Examples
    --------
    >>> relative_link("results/tables/claims.csv", "results/index.html")
    'tables/claims.csv'
    >>> relative_link("results/mitsuba/seeds/tables/statistics.md", "results/index.html")
    'mitsuba/seeds/tables/statistics.md'
    """
    rel = os.path.relpath(os.fspath(path), os.path.dirname(os.fspath(page)) or ".")
    return Path(rel).as_posix()
