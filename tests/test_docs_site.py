"""The built documentation as a reader sees it: every script from the site itself (MathJax
included, so the equations render offline), and at 1280 px a top navigation on one line and
API pages whose title and tables fit beside the right-hand contents.

The site is the one ``tests/test_docs.py`` checks (``docs_site``, built once a session).
"""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import urlsplit

import pytest

pytestmark = pytest.mark.xdist_group("test_docs")

#: MathJax as the site carries it (sphinx-mathjax-offline, docs/conf.py).
MATHJAX = "_static/mathjax/tex-chtml.js"
WIDTH = 1280


class _Assets(HTMLParser):
    """The ``src`` of every script and the ``href`` of every stylesheet of a page."""

    def __init__(self):
        super().__init__()
        self.scripts: list[str] = []
        self.styles: list[str] = []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "script" and attrs.get("src"):
            self.scripts.append(attrs["src"])
        elif tag == "link" and "stylesheet" in (attrs.get("rel") or "") and attrs.get("href"):
            self.styles.append(attrs["href"])


def pages(site: Path) -> list[Path]:
    """The site's pages (theme templates copied under ``_static`` are not pages)."""
    return [p for p in sorted(site.rglob("*.html")) if "_static" not in p.parts]


def test_every_script_and_stylesheet_comes_from_the_site_mathjax_included(docs_site):
    assert (docs_site / MATHJAX).is_file(), f"{MATHJAX} is not in the built site"
    with_math = 0
    for page in pages(docs_site):
        text = page.read_text(encoding="utf-8")
        assets = _Assets()
        assets.feed(text)
        for url in assets.scripts + assets.styles:
            parts = urlsplit(url)
            assert not parts.scheme and not parts.netloc, f"{page.name} loads {url}"
            target = (page.parent / parts.path).resolve()
            assert target.is_file(), f"{page.name} loads {url}, which is not in the site"
        if re.search(r'class="math[ "]', text):
            with_math += 1
            loaded = [(page.parent / urlsplit(s).path).resolve() for s in assets.scripts]
            assert (docs_site / MATHJAX).resolve() in loaded, f"{page.name}: no local MathJax"
    assert with_math >= 5, "expected pages with equations (index, uncertainty, the API)"


#: Measured in the page at 1280 px: the header's navigation links (text, top, height and
#: line height), elements whose content is cut or scrolls sideways, the page title's text
#: box and the right-hand contents' box, and how many equations MathJax typeset.
MEASURE = r"""(() => {
  const box = r => r && {left: r.left, right: r.right, top: r.top, bottom: r.bottom};
  const links = [...document.querySelectorAll('.bd-header .navbar-header-items .nav-link')]
    .filter(a => a.offsetParent !== null)
    .map(a => ({text: a.innerText.trim(), top: Math.round(a.getBoundingClientRect().top),
                height: a.getBoundingClientRect().height,
                line: parseFloat(getComputedStyle(a).lineHeight)
                      || 1.2 * parseFloat(getComputedStyle(a).fontSize)}));
  // MathJax keeps a screen-reader copy of each equation (mjx-assistive-mml), clipped to
  // nothing and wider than the typeset math; code blocks scroll sideways by design.
  const overflowing = [...document.querySelectorAll('body *')]
    .filter(e => !e.closest('.math, mjx-container, pre'))
    .filter(e => getComputedStyle(e).overflowX !== 'visible' && e.scrollWidth > e.clientWidth + 1)
    .map(e => `${e.tagName.toLowerCase()}.${e.className} ${e.scrollWidth} > ${e.clientWidth}`);
  const h1 = document.querySelector('article h1');
  let title = null;
  if (h1) {
    const range = document.createRange();
    range.selectNodeContents(h1);
    title = box(range.getBoundingClientRect());
  }
  const side = document.querySelector('.bd-sidebar-secondary');
  return {links, overflowing, title, side: side && side.offsetParent !== null
          ? box(side.getBoundingClientRect()) : null,
          equations: document.querySelectorAll('mjx-container').length,
          scroll: [document.documentElement.scrollWidth, document.documentElement.clientWidth]};
})()"""


def longest_api_page(site: Path) -> str:
    return max((p.name for p in (site / "api").glob("stereovar.*.html")), key=len)


#: The front page; the API page with the widest summary table (the result paths); the one with
#: the longest right-hand contents entries (Class.method()); the longest module name.
SCREENS = ["index.html", "api/stereovar.layout.html", "api/stereovar.estimators.base.html",
           "longest"]  # fmt: skip


@pytest.mark.parametrize("name", SCREENS)
def test_at_1280_px_the_navigation_is_one_line_and_pages_fit(
    docs_site, headless_chromium, name, tmp_path
):
    if name == "longest":
        name = f"api/{longest_api_page(docs_site)}"
    shown = headless_chromium(docs_site / name, width=WIDTH, height=900, expression=MEASURE)
    (tmp_path / Path(name).with_suffix(".png").name).write_bytes(shown.screenshot)
    m = shown.value
    failed = [e for e in shown.errors if e.startswith("network")]
    assert not failed, f"{name}: failed loads {failed}"

    links = m["links"]
    assert len(links) >= 4, f"{name}: expected the header's links, got {links}"
    assert len({link["top"] for link in links}) == 1, f"{name}: the navigation wraps: {links}"
    for link in links:
        assert link["height"] < 1.5 * link["line"], f"{name}: {link['text']!r} wraps"

    assert m["scroll"][0] <= m["scroll"][1], f"{name}: the page scrolls sideways {m['scroll']}"
    assert not m["overflowing"], f"{name}: content cut off or scrolling: {m['overflowing']}"

    title, side = m["title"], m["side"]
    assert title is not None, f"{name}: no page title"
    if side is not None:  # a page without sections has no right-hand contents
        meets = title["right"] > side["left"] and title["bottom"] > side["top"]
        assert not meets, f"{name}: the title {title} runs into the right-hand contents {side}"
    if name == "index.html":  # Eq. 1-3, typeset by the site's own MathJax
        assert m["equations"] >= 3, f"{name}: MathJax typeset {m['equations']} equations"


class _Images(HTMLParser):
    def __init__(self):
        super().__init__()
        self.images: list[str] = []

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            self.images.append(dict(attrs).get("src", ""))


@pytest.mark.parametrize("name", ["guide.html", "audit.html"])
def test_the_guide_and_the_audit_page_show_figures_of_a_tiny_run(docs_site, name):
    parser = _Images()
    parser.feed((docs_site / name).read_text(encoding="utf-8"))
    assert parser.images, f"{name} shows no figure"
    for src in parser.images:
        assert (docs_site / src).is_file(), f"{name}: {src} is not in the site"


def test_the_committed_figures_are_small_and_each_is_shown():
    folder = Path(__file__).resolve().parents[1] / "docs" / "figures"
    figures = sorted(folder.glob("*.png"))
    assert figures
    sources = "".join(p.read_text(encoding="utf-8") for p in folder.parent.glob("*.md"))
    for png in figures:
        assert png.stat().st_size < 150 * 1024, f"{png.name}: {png.stat().st_size} bytes"
        assert f"figures/{png.name}" in sources, f"{png.name} is on no page"
