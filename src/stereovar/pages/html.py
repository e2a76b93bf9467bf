"""The blocks every self-contained page shares: the document, a table, a figure, a link.

A page is one HTML file with its own stylesheet (the tables' stylesheet of
:func:`stereovar.io.tables.to_html` plus the page's), no script and nothing loaded from a
server: figures are PNG files beside it (a relative path) or embedded in it
(:func:`data_uri`), links are relative to the page's folder (:func:`relative_link`).
"""

from __future__ import annotations

import base64
import html
import os
from pathlib import Path

from ..io.tables import to_html

__all__ = ["data_uri", "document", "figure", "relative_link", "table"]

_MIME = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".svg": "image/svg+xml"}


def document(title: str, body: list[str], css: str = "") -> str:
    """One self-contained HTML document.

    Parameters
    ----------
    title : str
        The page's ``<title>`` (escaped here).
    body : list of str
        The body's HTML fragments, in order, one per line.
    css : str, optional
        The page's own stylesheet, after the tables' (:func:`stereovar.io.tables.to_html`).

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
    page = to_html([], ["quantity"], caption=title)
    head = page[: page.index("<body>")].replace("</style>", css + "</style>", 1)
    return head + "<body>\n" + "\n".join(body) + "\n</body>\n</html>\n"


def table(rows: list[dict], columns: list[str], caption: str = "", digits: int = 4) -> str:
    """The ``<table>`` element of :func:`stereovar.io.tables.to_html`'s page (its numbers to
    ``digits`` significant digits, headers, cells and caption escaped).

    Examples
    --------
    >>> t = table([{"a": 1.23456, "b": "<x>"}], ["a", "b"], digits=3)
    >>> t.startswith("<table") and "1.23" in t and "&lt;x&gt;" in t
    True
    """
    page = to_html(rows, columns, caption=caption, digits=digits)
    return page[page.index("<body>") + len("<body>") : page.index("</body>")].strip()


def figure(src: str, caption_html: str, *, alt: str, ident: str = "") -> str:
    """A ``<figure>`` of one image with its caption.

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
    <figure id="fig-a"><img src="figures/a&amp;b.png" alt="a"
    style="max-width:100%"><figcaption>Fig. 1</figcaption></figure>
    """
    attrs = f' id="{html.escape(ident)}"' if ident else ""
    return (
        f'<figure{attrs}><img src="{html.escape(src)}" alt="{html.escape(alt)}" '
        f'style="max-width:100%"><figcaption>{caption_html}</figcaption></figure>'
    )


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
