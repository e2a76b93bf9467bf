"""Captions as the pages show them (stereovar.pages.captions): every report caption rendered
through docutils with MathML math, and no TeX left in the text a reader sees."""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path

import pytest
import yaml

from stereovar.pages.captions import caption_markup, render_caption, rst_to_html

REPO = Path(__file__).resolve().parents[1]
CAPTIONS = sorted((REPO / "workflow/report").glob("*.rst"))
TEX_MARKERS = ("_{", "^{", "\\", "$")
"""What TeX leaves in text that was not typeset: a braced sub- or superscript, a command, a
math delimiter."""
REPOSITORY_PATHS = re.compile(r"\b(workflow|docs|profiles|schemas|presets|src)/|snakemake --report")
"""Paths of the source repository, which an installed stereovar does not have."""


class VisibleText(HTMLParser):
    """The text a browser shows of an HTML fragment (MathML's token elements included; no
    ``annotation``, ``script`` or ``style``), and the MathML elements it holds."""

    HIDDEN = {"annotation", "annotation-xml", "script", "style"}

    def __init__(self, fragment: str):
        super().__init__(convert_charrefs=True)
        self.parts: list[str] = []
        self.tags: list[str] = []
        self._hidden = 0
        self.feed(fragment)
        self.text = "".join(self.parts)

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        self._hidden += tag in self.HIDDEN

    def handle_endtag(self, tag):
        self._hidden -= tag in self.HIDDEN

    def handle_data(self, data):
        if not self._hidden:
            self.parts.append(data)


@pytest.fixture(scope="module")
def config() -> dict:
    """The default config (the one a new run starts from)."""
    return yaml.safe_load((REPO / "config.yaml").read_text())


def test_every_report_caption_renders_without_tex_markers(config):
    assert len(CAPTIONS) >= 20
    math_seen = 0
    for path in CAPTIONS:
        fragment = rst_to_html(render_caption(path.read_text(encoding="utf-8"), config))
        shown = VisibleText(fragment)
        leaks = [m for m in TEX_MARKERS if m in shown.text]
        assert not leaks, (path.name, leaks, shown.text)
        assert "problematic" not in fragment and "system-message" not in fragment, path.name
        assert "{{" not in shown.text and "{%" not in shown.text, path.name  # Jinja filled
        assert not REPOSITORY_PATHS.search(shown.text), (path.name, shown.text)
        math_seen += "math" in shown.tags
    assert math_seen >= 3  # the captions with equations typeset them


def test_math_roles_become_mathml_with_the_subscripts_as_elements():
    fragment = rst_to_html(r"The pair (:math:`\sigma^2_L`, :math:`\hat\sigma^2_{R\to L}`).")
    shown = VisibleText(fragment)
    assert not [m for m in TEX_MARKERS if m in shown.text]
    assert shown.tags.count("math") == 2
    assert "msubsup" in shown.tags and "mover" in shown.tags  # σ̂ with sub- and superscript
    # the tokens in reading order: σ 2 L, then σ ˆ R → L 2 (MathML puts base, sub, sup)
    assert re.sub(r"\s+", "", shown.text) == "Thepair(σL2,σˆR→L2)."


def test_caption_text_is_escaped_and_carries_no_raw_html():
    text = "a <img src=x onerror=alert(1)> & **b**\n\n.. raw:: html\n\n   <script>x</script>"
    fragment = str(caption_markup(text))
    assert "<img" not in fragment and "<script" not in fragment
    assert "&lt;img" in fragment and "<strong>b</strong>" in fragment


def test_unknown_jinja_names_render_empty():
    text = "Frame {{ snakemake.wildcards.frame }} at SPP {{ snakemake.config['render']['spp'] }}."
    assert render_caption(text, {}) == "Frame  at SPP ."
