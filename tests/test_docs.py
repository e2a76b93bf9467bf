"""The documentation site builds warnings-as-errors, its generated pages cover the schema and
the code, and README.md stays short with working links."""

from __future__ import annotations

import ast
import html
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
SRC = REPO / "src" / "stereovar"
SCHEMA = REPO / "workflow" / "schemas" / "config.schema.yaml"
README_LIMIT = 10 * 1024


@pytest.fixture(scope="module")
def site(docs_site) -> Path:
    """The documentation built as ``make docs`` builds it (``docs_site``, tests/conftest.py)."""
    return docs_site


class _Text(HTMLParser):
    """A page's visible text and its table rows (cell texts), scripts and styles left out."""

    def __init__(self):
        super().__init__()
        self.parts: list[str] = []
        self.rows: list[list[str]] = []
        self._skip = 0
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        if tag in ("script", "style"):
            self._skip += 1
        elif tag == "tr":
            self.rows.append([])
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag in ("script", "style"):
            self._skip -= 1
        elif tag in ("td", "th") and self._cell is not None and self.rows:
            self.rows[-1].append(" ".join("".join(self._cell).split()))
            self._cell = None

    def handle_data(self, data):
        if self._skip:
            return
        self.parts.append(data)
        if self._cell is not None:
            self._cell.append(data)

    @property
    def text(self) -> str:
        return " ".join("".join(self.parts).split())


_TYPOGRAPHY = str.maketrans({"\u201c": '"', "\u201d": '"', "\u2018": "'", "\u2019": "'"})


def plain(text: str) -> str:
    """Text as written in a source file: Sphinx's smart quotes and dashes undone."""
    return text.translate(_TYPOGRAPHY).replace("\u2014", "---").replace("\u2013", "--")


def page(site: Path, name: str) -> _Text:
    parser = _Text()
    parser.feed((site / name).read_text(encoding="utf-8"))
    return parser


def schema_keys(schema: dict, prefix: str = ""):
    for name, sub in (schema.get("properties") or {}).items():
        yield f"{prefix}{name}", sub
        yield from schema_keys(sub, f"{prefix}{name}.")


def public_modules() -> list[str]:
    """Every module of the package that is not private, by walking the source tree."""
    names = []
    for path in sorted(SRC.rglob("*.py")):
        parts = path.relative_to(SRC.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if any(part.startswith("_") for part in parts):
            continue
        names.append(".".join(parts))
    return names


# --- the build and the generated pages ------------------------------------------------------


def test_every_page_is_built(site):
    sources = [p for p in DOCS.glob("*.md")] + [p for p in DOCS.glob("*.rst")]
    assert sources, "no pages in docs/"
    for source in sources:
        assert (site / f"{source.stem}.html").is_file(), f"{source.name} was not built"


def test_configuration_page_lists_every_schema_key_with_its_default(site):
    schema = yaml.safe_load(SCHEMA.read_text(encoding="utf-8"))
    built = page(site, "configuration.html")
    rows = {row[0]: row for row in built.rows if row}
    keys = list(schema_keys(schema))
    assert len(keys) > 50
    for key, sub in keys:
        assert key in rows, f"config key {key} is not on the configuration page"
        row = rows[key]
        if sub.get("description"):
            words = " ".join(str(sub["description"]).replace("`", "").split())
            assert words[:40] in plain(row[4]), f"{key}: the schema's description is not in its row"
        if "default" in sub and not isinstance(sub["default"], (dict, list)):
            shown = yaml.safe_load(row[2].split(";")[0])
            assert shown == sub["default"], f"{key}: default {row[2]!r}, schema {sub['default']!r}"
        for value in sub.get("enum", []):
            if value is not None:
                assert str(value) in row[3], f"{key}: allowed value {value!r} not listed"


def test_layout_page_and_api_reference_cover_every_module(site):
    layout = page(site, "layout.html").text
    modules = public_modules()
    assert "stereovar.layout" in modules and "stereovar.io.images" in modules
    for name in modules:
        assert name in layout, f"module {name} is not on the layout page"
        assert (site / "api" / f"{name}.html").is_file(), f"no API page for {name}"


def test_layout_page_lists_every_result_path_function(site):
    """Every function of stereovar.layout whose docstring names a path under results/ is
    listed (and linked) among the result paths of the layout page; the functions are read
    from the module's source, not imported."""
    tree = ast.parse((SRC / "layout.py").read_text(encoding="utf-8"))
    functions = [
        node.name
        for node in tree.body
        if isinstance(node, ast.FunctionDef)
        and not node.name.startswith("_")
        and re.search(r"``results/[^`]", ast.get_docstring(node) or "")
    ]
    assert len(functions) > 20
    raw = (site / "layout.html").read_text(encoding="utf-8")
    section = raw[raw.index('id="result-paths"') :]
    for name in functions:
        assert f'href="api/stereovar.layout.html#stereovar.layout.{name}"' in section, (
            f"stereovar.layout.{name} is not among the result paths of the layout page"
        )


def _math_blocks(source: str) -> list[str]:
    """The equations of the ``.. math::`` blocks in the docstrings that autodoc documents:
    the module's, and those of its public functions, classes and their public methods."""
    tree = ast.parse(source)
    docs = [ast.get_docstring(tree)]
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and not node.name.startswith("_"):
            docs.append(ast.get_docstring(node))
            if isinstance(node, ast.ClassDef):
                docs += [
                    ast.get_docstring(item)
                    for item in node.body
                    if isinstance(item, ast.FunctionDef) and not item.name.startswith("_")
                ]
    blocks = []
    for doc in filter(None, docs):
        lines = doc.splitlines()
        for i, line in enumerate(lines):
            if not line.strip().startswith(".. math::"):
                continue
            indent = len(line) - len(line.lstrip())
            body = [line.strip()[len(".. math::") :].strip()]
            for nxt in lines[i + 1 :]:
                if nxt.strip() and len(nxt) - len(nxt.lstrip()) <= indent:
                    break
                if not "".join(body) and nxt.strip().startswith(":"):
                    continue  # a directive option (:label:, :nowrap:)
                body.append(nxt.strip())
            # blank-line separated equations are rendered as the lines of one display
            equations = "\n".join(body).split("\n\n")
            blocks += [" ".join(eq.split()) for eq in equations if eq.strip()]
    return blocks


def test_every_math_block_of_a_docstring_is_rendered_for_mathjax(site):
    checked = 0
    for name in public_modules():
        path = SRC.parent.joinpath(*name.split("."))
        # a module beside a folder of the same name (pages/templates.py, pages/templates/)
        module = path.with_suffix(".py")
        path = module if module.is_file() else path / "__init__.py"
        blocks = _math_blocks(path.read_text(encoding="utf-8"))
        if not blocks:
            continue
        raw = (site / "api" / f"{name}.html").read_text(encoding="utf-8")
        assert re.search(r"<script[^>]+mathjax", raw, re.I), f"{name}: MathJax is not loaded"
        rendered = [
            "".join(html.unescape(m).split())
            for m in re.findall(r'<div class="math[^"]*">(.*?)</div>', raw, re.S)
        ]
        for block in blocks:
            squeezed = "".join(block.split())
            assert any(squeezed in r for r in rendered), (
                f"{name}: the math block {block[:60]!r} is not rendered as MathJax display math"
            )
        checked += len(blocks)
    assert checked >= 5, "expected docstrings with math blocks (Eq. 1-3 at least)"


def test_command_options_are_documented(site):
    from stereovar.cli import build_parser

    text = page(site, "getting-started.html").text
    parser = build_parser()
    commands = [
        name
        for action in parser._actions
        if action.__class__.__name__ == "_SubParsersAction"
        for name in action.choices
    ]
    assert {"init", "run", "audit", "report", "export"} <= set(commands)
    for name in commands:
        assert f"stereovar {name} --help" in text, f"stereovar {name} has no help on the page"
        assert f"usage: stereovar {name}" in text


# --- README.md -------------------------------------------------------------------------------


def test_readme_is_at_most_10_kb():
    size = (REPO / "README.md").stat().st_size
    assert size <= README_LIMIT, f"README.md is {size} bytes, the limit is {README_LIMIT}"


def test_readme_relative_links_resolve():
    text = (REPO / "README.md").read_text(encoding="utf-8")
    links = re.findall(r"\]\(([^)\s]+)\)", text)
    relative = [link for link in links if not re.match(r"[a-z]+:|#", link)]
    assert relative, "README.md links none of the documentation pages"
    for link in relative:
        target = (REPO / link.split("#")[0]).resolve()
        assert target.exists(), f"README.md links {link}, which is not in the repository"
        assert REPO in target.parents, f"README.md links {link}, outside the repository"
