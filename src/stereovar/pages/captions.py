"""The report's captions (``workflow/report/*.rst``) as page text.

Snakemake's report renders each caption with Jinja (``{{ snakemake.config[...] }}``) and
then as reStructuredText. A page needs only the inline markup the captions use:
:func:`render_caption` fills the Jinja expressions from the run's config, and
:func:`rst_to_html` turns ``**bold**``, ``*italic*``, double-backquoted code and
``:math:`` roles into HTML, one ``<p>`` per paragraph.
"""

from __future__ import annotations

import html
import re
from types import SimpleNamespace

__all__ = ["render_caption", "rst_to_html"]

_LATEX = {
    r"\sigma": "σ",
    r"\epsilon": "ε",
    r"\varepsilon": "ε",
    r"\rho": "ρ",
    r"\mu": "μ",
    r"\Omega": "Ω",
    r"\setminus": "∖",
    r"\cap": "∩",
    r"\ln": "ln",
    r"\to": "→",
    r"\hat": "",
}
_LATEX_NAME = re.compile(r"\\[A-Za-z]+")
_SUBSCRIPT = re.compile(r"_(\{[^{}]*\}|\\?[A-Za-z0-9]+)")
_SUPERSCRIPT = re.compile(r"\^(\{[^{}]*\}|[A-Za-z0-9]+)")
_CODE = re.compile(r"``(.+?)``", re.S)
_MATH = re.compile(r":math:`(.+?)`", re.S)
_BOLD = re.compile(r"\*\*(.+?)\*\*", re.S)
_ITALIC = re.compile(r"(?<![\w*])\*(?!\s)(.+?)(?<!\s)\*(?![\w*])", re.S)


def render_caption(text: str, config: dict) -> str:
    """A caption's Jinja expressions filled from ``config``, as Snakemake's report fills
    them (``snakemake.config``); an expression naming anything else, such as a job's
    wildcards, renders empty.

    Examples
    --------
    >>> render_caption('SPP {{ snakemake.config["render"]["spp"] }}', {"render": {"spp": 64}})
    'SPP 64'
    >>> render_caption("{{ snakemake.config['scenes'] | length }} scenes", {"scenes": ["a", "b"]})
    '2 scenes'
    """
    import jinja2

    template = jinja2.Environment(autoescape=False).from_string(text)
    return template.render(snakemake=SimpleNamespace(config=config))


def _math(tex: str) -> str:
    """A ``:math:`` role's LaTeX as plain HTML: Greek letters and a few operators as
    characters, ``_x`` and ``^x`` as sub- and superscripts (``tex`` is already escaped)."""

    def name(match):
        return _LATEX.get(match.group(), match.group()[1:])

    def script(tag):
        def replace(match):
            body = match.group(1)
            body = body[1:-1] if body.startswith("{") else body
            return f"<{tag}>{_LATEX_NAME.sub(name, body)}</{tag}>"

        return replace

    out = _SUBSCRIPT.sub(script("sub"), tex)
    out = _SUPERSCRIPT.sub(script("sup"), out)
    out = _LATEX_NAME.sub(name, out).replace("{", "").replace("}", "")
    return f'<span class="math">{out}</span>'


def _inline(paragraph: str) -> str:
    """One paragraph's inline markup as HTML (see :func:`rst_to_html`)."""
    kept: list[str] = []

    def keep(fragment: str) -> str:
        kept.append(fragment)
        return f"\x00{len(kept) - 1}\x00"

    body = html.escape(" ".join(paragraph.split()), quote=False)
    body = _CODE.sub(lambda m: keep(f"<code>{m.group(1)}</code>"), body)
    body = _MATH.sub(lambda m: keep(_math(m.group(1))), body)
    body = _BOLD.sub(r"<b>\1</b>", body)
    body = _ITALIC.sub(r"<i>\1</i>", body)
    return re.sub("\x00(\\d+)\x00", lambda m: kept[int(m.group(1))], body)


def rst_to_html(text: str) -> str:
    """A caption's reStructuredText inline markup as HTML: one ``<p>`` per paragraph, the
    text escaped, ``**bold**`` and ``*italic*``, double-backquoted literals as ``<code>``
    (their content kept as written) and ``:math:`` roles as text with sub- and superscripts.

    Examples
    --------
    >>> rst_to_html("**Fig. 1.** The ``a_b`` field < 1.")
    '<p><b>Fig. 1.</b> The <code>a_b</code> field &lt; 1.</p>'
    >>> rst_to_html(":math:`C_\\\\sigma`")
    '<p><span class="math">C<sub>σ</sub></span></p>'
    >>> rst_to_html("one\\n\\ntwo")
    '<p>one</p>\\n<p>two</p>'
    """
    paragraphs = [p.strip() for p in re.split(r"\n\s*\n", text.strip()) if p.strip()]
    return "\n".join(f"<p>{_inline(p)}</p>" for p in paragraphs)
