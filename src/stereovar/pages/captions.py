"""The report's captions (``workflow/report/*.rst``) as page text.

Snakemake's report renders each caption with Jinja (``{{ snakemake.config[...] }}``) and
then as reStructuredText. A page does the same: :func:`render_caption` fills the Jinja
expressions from the run's config, and :func:`rst_to_html` renders the text with docutils,
its ``:math:`` roles as MathML (docutils' ``math_output = "MathML"``), so an equation is
typeset by the browser and no TeX reaches the reader. :func:`caption_markup` is the same as
:class:`markupsafe.Markup`, the templates' ``caption`` filter.
"""

from __future__ import annotations

from functools import lru_cache
from types import SimpleNamespace

__all__ = ["caption_markup", "render_caption", "rst_to_html"]

DOCUTILS_SETTINGS = {
    "math_output": "MathML",
    "report_level": 5,  # no system messages in the output
    "halt_level": 5,
    "doctitle_xform": False,  # a caption's first line is text, not a document title
    "sectsubtitle_xform": False,
    "file_insertion_enabled": False,  # a caption reads no file
    "raw_enabled": False,  # and carries no raw HTML
    "syntax_highlight": "none",
    "_disable_config": True,  # no docutils.conf of the user's changes the pages
    "input_encoding": "unicode",
    "output_encoding": "unicode",
}
"""docutils' settings for captions: MathML math, quiet, nothing read or passed through."""


def render_caption(text: str, config: dict) -> str:
    """A caption's Jinja expressions filled from ``config``, as Snakemake's report fills
    them (``snakemake.config``); an expression naming anything else, such as a job's
    wildcards or a key the config lacks, renders empty.

    Examples
    --------
    >>> render_caption('SPP {{ snakemake.config["render"]["spp"] }}', {"render": {"spp": 64}})
    'SPP 64'
    >>> render_caption("{{ snakemake.config['scenes'] | length }} scenes", {"scenes": ["a", "b"]})
    '2 scenes'
    >>> render_caption("frame {{ snakemake.wildcards.frame }}.", {})
    'frame .'
    """
    import jinja2

    template = jinja2.Environment(autoescape=False, undefined=jinja2.ChainableUndefined)
    template = template.from_string(text)
    return template.render(snakemake=SimpleNamespace(config=config))


@lru_cache(maxsize=256)
def rst_to_html(text: str) -> str:
    """A caption's reStructuredText as an HTML fragment (docutils' ``html5`` writer): one
    ``<p>`` per paragraph, the text escaped, ``:math:`` roles as MathML, literals as
    ``<span class="docutils literal">``.

    Parameters
    ----------
    text : str
        reStructuredText (its Jinja already filled, :func:`render_caption`).

    Returns
    -------
    str
        The fragment; ``""`` for blank text.

    Examples
    --------
    >>> rst_to_html("**Fig. 1.** The ``a_b`` field < 1.")
    '<p><strong>Fig. 1.</strong> The <span class="docutils literal">a_b</span> field &lt; 1.</p>'
    >>> print(rst_to_html(":math:`C_\\\\sigma`"))  # doctest: +NORMALIZE_WHITESPACE
    <p><math xmlns="http://www.w3.org/1998/Math/MathML">
      <msub> <mi>C</mi> <mi>σ</mi> </msub>
    </math></p>
    >>> rst_to_html("one\\n\\ntwo")
    '<p>one</p>\\n<p>two</p>'
    """
    from docutils.core import publish_parts

    if not text.strip():
        return ""
    parts = publish_parts(text, writer_name="html5", settings_overrides=DOCUTILS_SETTINGS)
    return parts["fragment"].strip()


def caption_markup(text: str):
    """:func:`rst_to_html` as :class:`markupsafe.Markup`, for a template to print as it is
    (the templates' ``caption`` filter).

    Examples
    --------
    >>> caption_markup("*a* & b")
    Markup('<p><em>a</em> &amp; b</p>')
    """
    from markupsafe import Markup

    return Markup(rst_to_html(str(text or "")))
