"""Every Examples section of the library runs as a doctest."""

import ast
import doctest
import importlib
import pkgutil
from pathlib import Path

import pytest

import stereovar

MODULES = sorted(m.name for m in pkgutil.walk_packages(stereovar.__path__, "stereovar."))

PACKAGE = Path(stereovar.__file__).parent

KEY_EXAMPLES = [
    "stereovar.estimators.seeds.variance_field",  # Eq. 1
    "stereovar.estimators.seeds.StreamingVariance",  # Eq. 1, streamed
    "stereovar.statistics.warp.warp_right_to_left",  # Eq. 2
    "stereovar.statistics.warp.align_variance",  # Eq. 2 and the valid set of Eq. 3
    "stereovar.statistics.correlation.pearson_over_mask",  # Eq. 3
    "stereovar.statistics.correlation.fisher_interval",
    "stereovar.statistics.bootstrap.percentile_interval",  # the block bootstrap's interval
    "stereovar.statistics.bootstrap.tile_sums",
    "stereovar.statistics.bootstrap.bootstrap_replicates",
    "stereovar.controls.partial.partial_pair",  # the partial (intensity-controlled) rho
    "stereovar.controls.intensity.intensity_residuals",
    "stereovar.audit.run.discover_audit",  # what `stereovar audit` calls first
]
"""The public functions whose Examples the documentation points to (paper Eq. 1-3, the
bootstrap, the partial correlation and the audit's entry point)."""

WITH_EQUATION = [
    n
    for n in KEY_EXAMPLES
    if n.rpartition(".")[2] not in {"tile_sums", "bootstrap_replicates", "discover_audit"}
]
"""Those that state an equation (the others compute sums, replicates or find files)."""


def _source_files() -> list:
    """The package's Python files, outside ``__pycache__`` and private data folders (a name
    starting with one underscore, e.g. the workflow an installed wheel carries)."""
    return sorted(
        p
        for p in PACKAGE.rglob("*.py")
        if not any(d.startswith("_") for d in p.relative_to(PACKAGE).parts[:-1])
    )


def _module_names_from_files() -> set:
    """Every module of the package by its file, independently of pkgutil."""
    names = set()
    for path in _source_files():
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        names.add(".".join(parts))
    return names


def test_the_walk_reaches_every_module_file():
    assert _module_names_from_files() - {"stereovar"} == set(MODULES)


@pytest.mark.parametrize("name", MODULES)
def test_examples_run(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # an example that writes a relative path writes it here
    module = importlib.import_module(name)
    result = doctest.testmod(
        module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, verbose=False
    )
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {name}"


def _resolve(dotted: str):
    module, _, name = dotted.rpartition(".")
    return importlib.import_module(module), getattr(importlib.import_module(module), name)


@pytest.mark.parametrize("dotted", KEY_EXAMPLES)
def test_key_functions_have_examples_that_the_walk_runs(dotted):
    module, obj = _resolve(dotted)
    assert module.__name__ in MODULES
    doc = obj.__doc__ or ""
    assert "\n    Examples\n    --------\n" in doc, f"{dotted} has no numpydoc Examples section"
    finder = doctest.DocTestFinder(recurse=False)
    examples = [e for t in finder.find(obj, dotted, module=module) for e in t.examples]
    assert len(examples) >= 2, f"{dotted}: {len(examples)} doctest examples"


@pytest.mark.parametrize("dotted", WITH_EQUATION)
def test_key_functions_state_their_equation_in_a_math_block(dotted):
    _, obj = _resolve(dotted)
    doc = obj.__doc__ or ""
    assert ".. math::\n" in doc, f"{dotted}: no .. math:: block"
    assert "Sec. " in doc, f"{dotted}: the paper section is not named (nor that it has none)"


CONTROL = {"\a", "\b", "\f", "\r", "\v", "\x00"}


def _docstrings(tree):
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            doc = ast.get_docstring(node, clean=False)
            if doc:
                yield getattr(node, "name", "<module>"), doc


@pytest.mark.parametrize(
    "path",
    _source_files(),
    ids=lambda p: p.relative_to(PACKAGE).as_posix(),
)
def test_docstrings_hold_no_control_characters(path):
    """A backslash escape in a non-raw docstring (``\\rho`` written ``\rho``) becomes a control
    character that breaks the rendered maths."""
    bad = [name for name, doc in _docstrings(ast.parse(path.read_text())) if CONTROL & set(doc)]
    assert not bad, f"{path.name}: control characters in the docstrings of {bad}"
