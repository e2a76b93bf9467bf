"""The house: no import circle among the package's modules and no module over 600 lines.

An import counts wherever it stands (a module's top, or inside a function, where circles
hide), ``from . import x`` included; two modules that reach each other through any chain
form a circle (a strongly connected component of the import graph). The checker is shown to
find a circle planted in a throwaway package, and a module of 601 lines.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "stereovar"

MAX_LINES = 600
"""Lines a module may have."""


def modules(package: Path) -> dict[str, Path]:
    """Dotted name to file of every module of ``package`` (a package is its ``__init__``)."""
    out = {}
    for path in sorted(package.rglob("*.py")):
        parts = list(path.relative_to(package.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def import_graph(package: Path) -> dict[str, set[str]]:
    """Module to the package's modules it imports, at any depth of its code."""
    found = modules(package)
    graph: dict[str, set[str]] = {name: set() for name in found}
    for name, path in found.items():
        here = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            targets = []
            if isinstance(node, ast.ImportFrom):
                base = here[: len(here) - node.level + 1] if node.level else []
                module = ".".join(base + ([node.module] if node.module else []))
                targets = [module] + [f"{module}.{alias.name}" for alias in node.names]
            elif isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            graph[name] |= {t for t in targets if t in found and t != name}
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    sys.setrecursionlimit(max(10_000, sys.getrecursionlimit()))
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def long_modules(package: Path, limit: int = MAX_LINES) -> dict[str, int]:
    """Modules over ``limit`` lines, with their line counts."""
    counts = {name: len(path.read_text().splitlines()) for name, path in modules(package).items()}
    return {name: n for name, n in counts.items() if n > limit}


def test_no_import_circle_among_the_modules():
    assert circles(import_graph(PACKAGE)) == []


def test_no_module_over_600_lines():
    assert long_modules(PACKAGE) == {}


@pytest.fixture
def planted(tmp_path) -> Path:
    """A throwaway package: ``a`` imports ``b`` at its top, ``b`` imports ``c`` inside a
    function, ``c`` imports ``a`` through ``from . import``; ``d`` only imports ``a``; ``e``
    has 601 lines."""
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from .sub import b\n")
    (pkg / "sub" / "b.py").write_text("def f():\n    from ..c import x\n    return x\n")
    (pkg / "c.py").write_text("from . import a\nx = 1\n")
    (pkg / "d.py").write_text("import pkg.a\n")
    (pkg / "e.py").write_text("x = 1\n" * 601)
    return pkg


def test_the_checker_finds_a_planted_circle_and_a_long_module(planted):
    graph = import_graph(planted)
    assert graph["pkg.a"] == {"pkg.sub", "pkg.sub.b"}
    assert graph["pkg.sub.b"] == {"pkg.c"}
    assert graph["pkg.d"] == {"pkg.a"}
    assert circles(graph) == [["pkg.a", "pkg.c", "pkg.sub.b"]]
    assert long_modules(planted) == {"pkg.e": 601}
    (planted / "c.py").write_text("x = 1\n")  # the circle broken: none left
    assert circles(import_graph(planted)) == []
