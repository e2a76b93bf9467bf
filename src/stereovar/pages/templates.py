"""The Jinja2 environment of every HTML page the package writes.

One environment (:func:`environment`) loads the templates of
``stereovar/pages/templates/`` with autoescaping on, so a page is written as a template and
its data, never assembled from strings: every value a template prints is HTML-escaped
unless it is :class:`markupsafe.Markup` (a caption rendered by
:func:`stereovar.pages.captions.caption_markup`, a fragment a macro made).

``base.html.j2``
    The document: ``<head>`` with the shared stylesheet (the tables' of
    :func:`stereovar.io.tables.to_html` and the pages' own), and the blocks ``title``,
    ``css`` (a page's own rules, after the shared ones) and ``body``. A page extends it.
``macros.html.j2``
    ``figure``, ``table``, ``verdict`` (a badge that carries its word) and ``links`` (a table
    of files by format); a template imports them with
    ``{% import "macros.html.j2" as m %}``.

Filters: ``caption`` (reStructuredText to HTML, :func:`~stereovar.pages.captions.caption_markup`),
``cell`` (a table cell's text, numbers to significant digits), ``significant``
(:func:`stereovar.pages.numbers.significant`). Globals: ``docs_page``
(:func:`stereovar.links.docs_page`) and ``table_css``.
"""

from __future__ import annotations

from functools import lru_cache

__all__ = ["environment", "render"]


def _cell(value, digits: int = 4) -> str:
    """A table cell's text: floats to ``digits`` significant digits (``NaN`` for NaN and
    None), as :func:`stereovar.io.tables.to_html` shows them; anything else as ``str``.

    Examples
    --------
    >>> _cell(3.14159, 3), _cell(None), _cell("a<b"), _cell(7)
    ('3.14', 'NaN', 'a<b', '7')
    """
    from ..io.tables import _cell as table_cell

    return table_cell(value, digits)


def _is_number(value) -> bool:
    """Whether a cell is numeric (right-aligned in a table).

    Examples
    --------
    >>> _is_number(1.5), _is_number(True), _is_number("1.5")
    (True, False, False)
    """
    import numbers

    return isinstance(value, numbers.Real) and not isinstance(value, bool)


@lru_cache(maxsize=1)
def environment():
    """The pages' :class:`jinja2.Environment`: templates from the package
    (``stereovar/pages/templates/``), autoescaping on, undefined names an error.

    Returns
    -------
    jinja2.Environment
        Shared and cached: add nothing to it; pass a page's data as the template's context.

    Examples
    --------
    >>> env = environment()
    >>> env.from_string("{{ x }}").render(x="<b>")
    '&lt;b&gt;'
    >>> env.from_string("{{ x | caption }}").render(x="**a** :math:`\\\\rho`")[:24]
    '<p><strong>a</strong> <m'
    """
    import jinja2

    from ..io.tables import _PAGE_CSS
    from ..links import docs_page
    from .captions import caption_markup
    from .numbers import significant

    env = jinja2.Environment(
        loader=jinja2.PackageLoader("stereovar.pages", "templates"),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
    )
    env.filters |= {"caption": caption_markup, "cell": _cell, "significant": significant}
    env.tests["number"] = _is_number
    env.globals |= {"docs_page": docs_page, "table_css": _PAGE_CSS}
    return env


def render(template: str, /, **context) -> str:
    """The template ``template`` (a name in ``stereovar/pages/templates/``) rendered with
    ``context``.

    Examples
    --------
    >>> page = render("document.html.j2", title="A & B", body=[], css="")
    >>> page.startswith("<!DOCTYPE html>"), "<title>A &amp; B</title>" in page
    (True, True)
    """
    return environment().get_template(template).render(**context)
