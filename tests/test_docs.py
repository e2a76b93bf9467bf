"""The documentation site builds warnings-as-errors, its generated pages cover the schema and
the code, the addresses the package's messages give exist on it, ``make docs`` needs only
the docs extra (no Blender, no PyTorch), and README.md stays short with working links."""

from __future__ import annotations

import ast
import html
import json
import os
import re
import shutil
import subprocess
import sys
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


def docs_page_calls() -> list[tuple[str, int, str, str | None]]:
    """Every ``docs_page(page[, anchor])`` call of the package with literal arguments: its
    file, line, page and anchor, read from the source."""
    calls = []
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            name = getattr(node, "func", None)
            name = getattr(name, "id", None) or getattr(name, "attr", None)
            if not (isinstance(node, ast.Call) and name == "docs_page"):
                continue
            args = [a.value if isinstance(a, ast.Constant) else None for a in node.args]
            if args and all(isinstance(a, str) for a in args):
                where = str(path.relative_to(SRC.parent))
                calls.append((where, node.lineno, args[0], args[1] if len(args) > 1 else None))
    return calls


def test_every_documentation_address_the_package_gives_is_a_page_of_the_site(site):
    """Messages, starter configs and pages link the site (stereovar.links.docs_page), never a
    path of the repository: each page and anchor they name is in the built site, and the
    single-render refusal names its page's address."""
    from stereovar.estimators.single import refusal
    from stereovar.links import docs_base

    calls = docs_page_calls()
    assert len(calls) >= 5, calls
    for where, line, name, anchor in calls:
        built = site / (f"{name}.html" if name else "index.html")
        assert built.is_file(), f"{where}:{line} links page {name!r}, which the site lacks"
        if anchor:
            text = built.read_text(encoding="utf-8")
            assert f'id="{anchor}"' in text, f"{where}:{line}: {name}.html has no #{anchor}"
    line = refusal()
    cited = re.findall(re.escape(docs_base()) + r"([\w-]+)\.html", line)
    assert cited == ["single_render"], line
    assert (site / "single_render.html").is_file()
    assert "docs/" not in line.replace(docs_base(), ""), line


# --- make docs: the docs extra alone --------------------------------------------------------


def test_make_docs_sets_up_the_docs_extra_alone_then_builds():
    if shutil.which("make") is None:
        pytest.skip("make is not installed")
    plan = subprocess.run(["make", "--no-print-directory", "-n", "docs"], cwd=REPO,
                          capture_output=True, text=True,
                          check=True).stdout.splitlines()  # fmt: skip
    assert plan[0] == "bash scripts/setup.sh --docs", plan
    assert not [c for c in plan if "setup.sh" in c and "--docs" not in c], plan
    assert any(" -m sphinx -W --keep-going -b html docs " in c for c in plan), plan
    assert not [c for c in plan if "pip install" in c or "snakemake" in c], plan


FAKE_PYTHON = """#!/bin/sh
# Runs Python as {python}, except `-m pip ...`, which it records in {log} and does not run.
if [ "$1" = -m ] && [ "$2" = pip ]; then
    shift 2
    echo "$*" >> "{log}"
    exit 0
fi
exec "{python}" "$@"
"""


def test_the_docs_set_up_installs_the_docs_extra_alone_and_once(tmp_path):
    """scripts/setup.sh --docs in a copy of the checkout whose .venv's Python records the pip
    commands it is given instead of running them: one ``pip install -e .[docs]``, no libLLVM,
    no chromium, nothing again while pyproject.toml is unchanged, nothing over the full
    set-up's .venv, and an unknown option refused."""
    (tmp_path / "scripts").mkdir()
    shutil.copy(REPO / "scripts" / "setup.sh", tmp_path / "scripts" / "setup.sh")
    shutil.copy(REPO / "pyproject.toml", tmp_path / "pyproject.toml")
    log = tmp_path / "pip.log"
    python = tmp_path / ".venv" / "bin" / "python"
    python.parent.mkdir(parents=True)
    python.write_text(FAKE_PYTHON.format(python=sys.executable, log=log))
    python.chmod(0o755)
    env = {**os.environ, "PYTHON": sys.executable, "PATH": os.environ.get("PATH", "")}

    def setup(*args):
        return subprocess.run(["bash", "scripts/setup.sh", *args], cwd=tmp_path, env=env,
                              capture_output=True, text=True)  # fmt: skip

    first = setup("--docs")
    assert first.returncode == 0, first.stderr
    assert log.read_text().splitlines() == [
        "install --quiet --disable-pip-version-check -e .[docs]"
    ]
    said = first.stdout + first.stderr
    assert "no Blender, no PyTorch" in said and "ready to build the documentation" in said
    assert "libLLVM" not in said and "chromium" not in said
    assert (tmp_path / ".venv" / ".stereovar-setup-docs").is_file()

    again = setup("--docs")
    assert again.returncode == 0 and "up to date" in again.stdout
    assert len(log.read_text().splitlines()) == 1, "pip ran again with pyproject.toml unchanged"

    stamp = (tmp_path / ".venv" / ".stereovar-setup-docs").read_text()
    (tmp_path / ".venv" / ".stereovar-setup-docs").unlink()
    (tmp_path / ".venv" / ".stereovar-setup").write_text(stamp)  # the full set-up's .venv
    full = setup("--docs")
    assert full.returncode == 0 and "the full set-up" in full.stdout
    assert len(log.read_text().splitlines()) == 1

    wrong = setup("--doc")
    assert wrong.returncode == 1 and "unknown option '--doc'" in wrong.stderr


#: Run in a new Python: the optional extras made unimportable, as where only the docs extra
#: is installed; then the Sphinx configuration, and every public module imported under
#: autodoc's mocks as the build imports it, the extras' mocks already loaded. Prints what it
#: found as JSON.
WITHOUT_EXTRAS = r"""
import importlib, json, runpy, sys
EXTRAS = ("torch", "bpy", "pyoidn")

class Absent:
    def find_spec(self, fullname, path=None, target=None):
        if fullname.partition(".")[0] in EXTRAS:
            raise ModuleNotFoundError(f"No module named {fullname!r}", name=fullname)

sys.meta_path.insert(0, Absent())
sys.argv = ["sphinx"]
conf = runpy.run_path(CONF)
from sphinx.ext.autodoc.mock import mock

failed = {}
for name in MODULES:
    with mock(conf["autodoc_mock_imports"]):
        try:
            for extra in EXTRAS:  # loaded by a module documented before, as in a build
                importlib.import_module(extra)
            importlib.import_module(name)
        except Exception as err:
            failed[name] = f"{type(err).__name__}: {err}"
real = sorted(n for n in EXTRAS if n in sys.modules)
print(json.dumps({"mocked": conf["autodoc_mock_imports"], "failed": failed, "real": real}))
"""


def test_the_sphinx_configuration_and_every_module_load_without_blender_or_pytorch():
    modules = public_modules()
    code = WITHOUT_EXTRAS.replace("CONF", repr(str(DOCS / "conf.py"))).replace(
        "MODULES", repr(modules)
    )
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    found = json.loads(proc.stdout.strip().splitlines()[-1])
    assert {"torch", "bpy", "pyoidn"} <= set(found["mocked"]), found["mocked"]
    assert not found["failed"], found["failed"]
    assert found["real"] == [], f"imported for real: {found['real']}"
    assert len(modules) > 100


def test_with_the_full_set_up_the_build_still_imports_no_optional_extra():
    """Where torch is installed, the configuration refuses it outside autodoc's mock, so the
    build behaves as with the docs extra alone."""
    pytest.importorskip("torch", reason="checks the full set-up, where torch is installed")
    code = (
        "import runpy, sys; sys.argv = ['sphinx']; runpy.run_path(CONF)\n"
        "try:\n    import torch\nexcept ModuleNotFoundError as err:\n    print('refused', err)\n"
    ).replace("CONF", repr(str(DOCS / "conf.py")))
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                          text=True, timeout=120)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("refused"), proc.stdout


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
