"""The built documentation as a reader sees it: every script from the site itself (MathJax
included, so the equations render offline), and at 1280 px a top navigation on one line,
API pages whose title and tables fit beside the right-hand contents, and, on every
hand-written page and the API pages with the longest code lines, code blocks as wide as
their lines and code in tables that breaks only between words.

The site is the one ``tests/test_docs.py`` checks (``docs_site``, built once a session).
"""

from __future__ import annotations

import json
import re
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import urlsplit

import pytest

pytestmark = pytest.mark.xdist_group("test_docs")

DOCS = Path(__file__).resolve().parents[1] / "docs"
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


# --- code at 1280 px, page by page --------------------------------------------------------


class _Browser:
    """One headless Chromium that opens page after page (the DevTools protocol on a pipe, as
    the ``headless_chromium`` fixture of ``tests/conftest.py`` speaks it, which starts a
    browser per page: about 2 s a page against 0.5 s here)."""

    def __init__(self, binary: str, width: int, height: int, timeout: float = 60.0):
        import fcntl
        import os
        import subprocess
        import tempfile

        self.timeout = timeout
        self.profile = tempfile.mkdtemp(prefix="chromium-profile-")
        to_browser, from_browser = os.pipe(), os.pipe()
        ends = [fcntl.fcntl(to_browser[0], fcntl.F_DUPFD, 10),
                fcntl.fcntl(from_browser[1], fcntl.F_DUPFD, 10)]  # fmt: skip

        def child_fds():
            os.dup2(ends[0], 3)
            os.dup2(ends[1], 4)

        self.proc = subprocess.Popen(
            [binary, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
             "--remote-debugging-pipe", f"--user-data-dir={self.profile}", "--no-first-run",
             f"--window-size={width},{height}", "about:blank"],
            preexec_fn=child_fds, close_fds=False, stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        for fd in (to_browser[0], from_browser[1], *ends):
            os.close(fd)
        self.write_fd, self.read_fd = to_browser[1], from_browser[0]
        self.buffer, self.events, self.counter = b"", [], 0
        targets = self.call("Target.getTargets")["targetInfos"]
        page = next(t for t in targets if t["type"] == "page")
        self.session = self.call(
            "Target.attachToTarget", {"targetId": page["targetId"], "flatten": True}
        )["sessionId"]
        self.call("Page.enable", session=self.session)
        self.call("Emulation.setDeviceMetricsOverride",
                  {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
                  session=self.session)  # fmt: skip

    def receive(self) -> dict:
        import os
        import select
        import time

        deadline = time.monotonic() + self.timeout
        while b"\0" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.read_fd], [], [], left)[0]:
                raise TimeoutError(f"Chromium did not answer within {self.timeout:.0f} s")
            chunk = os.read(self.read_fd, 1 << 20)
            if not chunk:
                raise RuntimeError("Chromium closed the DevTools pipe")
            self.buffer += chunk
        message, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(message)

    def call(self, method: str, params=None, session=None) -> dict:
        import os

        self.counter += 1
        message = {"id": self.counter, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self.write_fd, json.dumps(message).encode() + b"\0")
        while True:
            reply = self.receive()
            if reply.get("id") == self.counter:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]
            self.events.append(reply)

    def evaluate(self, path: Path, expression: str):
        """Open ``path``, wait for its load event, and return ``expression``'s value."""
        self.events.clear()
        self.call("Page.navigate", {"url": path.resolve().as_uri()}, session=self.session)
        while not any(e.get("method") == "Page.loadEventFired" for e in self.events):
            self.events.append(self.receive())
        result = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True},
                           session=self.session)  # fmt: skip
        if "exceptionDetails" in result:
            raise RuntimeError(f"{path.name}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def close(self) -> None:
        import os
        import shutil
        import subprocess

        try:
            self.call("Browser.close")
        except (OSError, RuntimeError, TimeoutError):
            pass
        for fd in (self.write_fd, self.read_fd):
            os.close(fd)
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.profile, ignore_errors=True)


@pytest.fixture(scope="module")
def browser():
    import shutil

    binary = next((b for b in ("chromium", "chromium-browser") if shutil.which(b)), None)
    if binary is None:
        pytest.skip("Chromium is not installed (Debian/Ubuntu: apt-get install chromium)")
    session = _Browser(binary, WIDTH, 900)
    yield session
    session.close()


class _CodeLines(HTMLParser):
    """The longest line, in characters, of a page's ``pre`` blocks."""

    def __init__(self):
        super().__init__()
        self.depth = 0
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.depth += tag == "pre"

    def handle_endtag(self, tag):
        self.depth -= tag == "pre" and self.depth > 0

    def handle_data(self, data):
        if self.depth:
            self.text.append(data)

    @property
    def longest(self) -> int:
        return max(map(len, "".join(self.text).splitlines()), default=0)


def longest_code_line(page: Path) -> int:
    parser = _CodeLines()
    parser.feed(page.read_text(encoding="utf-8"))
    return parser.longest


#: Measured in a page at 1280 px: each code block's width against its column's, each word of
#: the code in tables that takes more than one line, the article's width, the header's height
#: against the theme's, and whether the page's contents (the right-hand sidebar) can be
#: reached: shown, or folded into the drawer that the header's button opens (clicked here,
#: last, as it moves the contents into the drawer).
CODE_AT_1280 = r"""(() => {
  const wide = [...document.querySelectorAll('article pre')]
    .filter(p => p.scrollWidth > p.clientWidth)
    .map(p => `${p.scrollWidth} > ${p.clientWidth}: `
              + p.innerText.split('\n').reduce((a, b) => a.length >= b.length ? a : b, ''));
  const broken = [];
  for (const code of document.querySelectorAll('article table code')) {
    const words = code.querySelectorAll('span.pre');
    for (const word of (words.length ? words : [code]))
      if (word.getClientRects().length > 1) broken.push(word.innerText);
  }
  const article = document.querySelector('.bd-article-container');
  const header = document.querySelector('.bd-header');
  const side = document.querySelector('#pst-secondary-sidebar');
  const entries = side ? side.querySelectorAll('.page-toc a').length : 0;
  const shown = !!side && side.getBoundingClientRect().width > 0
                && getComputedStyle(side).visibility === 'visible'
                && getComputedStyle(side).position !== 'fixed';
  let drawer = null;
  const toggle = document.querySelector('button.secondary-toggle');
  if (entries && !shown && toggle && toggle.offsetParent !== null) {
    toggle.click();
    const dialog = document.querySelector('#pst-secondary-sidebar-modal');
    drawer = {open: dialog.open, entries: dialog.querySelectorAll('.page-toc a').length,
              visibility: getComputedStyle(dialog).visibility};
    dialog.close();
  }
  return {wide, broken, article: article.getBoundingClientRect().width,
          header: header.getBoundingClientRect().height,
          headerHeight: parseFloat(getComputedStyle(document.documentElement)
                                   .getPropertyValue('--pst-header-height'))
                        * parseFloat(getComputedStyle(document.documentElement).fontSize),
          entries, shown, drawer};
})()"""


def code_pages(site: Path, api_pages: int = 6) -> list[str]:
    """Every hand-written page, and the ``api_pages`` API pages with the longest code line."""
    written = sorted(p.name for p in site.glob("*.html") if (DOCS / f"{p.stem}.md").is_file()
                     or (DOCS / f"{p.stem}.rst").is_file())  # fmt: skip
    api = sorted((site / "api").glob("stereovar*.html"), key=longest_code_line, reverse=True)
    return written + [f"api/{p.name}" for p in api[:api_pages]]


def test_at_1280_px_code_fits_its_column_and_code_in_tables_keeps_its_words(docs_site, browser):
    pages = code_pages(docs_site)
    assert len(pages) >= 25 and "generators.html" in pages, pages
    problems = []
    for name in pages:
        m = browser.evaluate(docs_site / name, CODE_AT_1280)
        problems += [f"{name}: code block wider than its column, {w}" for w in m["wide"]]
        problems += [f"{name}: {word!r} in a table broken over lines" for word in m["broken"]]
        if m["article"] < 0.75 * WIDTH:
            problems.append(f"{name}: the article is {m['article']:.0f} px wide")
        if m["header"] > m["headerHeight"] + 1:
            problems.append(f"{name}: the header is {m['header']:.0f} px high (wraps)")
        if m["entries"] and not m["shown"]:
            drawer = m["drawer"]
            if not (drawer and drawer["open"] and drawer["entries"] == m["entries"]
                    and drawer["visibility"] == "visible"):
                problems.append(f"{name}: its contents are hidden and no drawer shows them "
                                f"({drawer})")
    assert not problems, "\n".join(problems)
