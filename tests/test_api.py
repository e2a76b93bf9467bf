"""The public API: every listed name resolves, ``dir`` and the stub list them, the deprecated
Mitsuba aliases warn, every subpackage is a documented package, and the import stays cheap."""

import ast
import importlib
import json
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

import stereovar
import stereovar.renderers.mitsuba as mitsuba

PACKAGE = Path(stereovar.__file__).parent

MITSUBA_ONLY = {
    "load_mitsuba": "stereovar.renderers.mitsuba.backend",
    "select_variant": "stereovar.renderers.mitsuba.backend",
    "load_scene": "stereovar.renderers.mitsuba.scene",
    "render_view": "stereovar.renderers.mitsuba.render",
    "MitsubaScene": "stereovar.renderers.mitsuba",
}
"""Where each Mitsuba-only name is defined (written out here, not read from the package)."""


def _public():
    return [n for n in stereovar.__all__ if n != "__version__"]


@pytest.mark.parametrize("name", sorted(stereovar._API))
def test_every_public_name_resolves_to_its_module(name):
    obj = getattr(stereovar, name)
    assert getattr(importlib.import_module(f"stereovar.{stereovar._API[name]}"), name) is obj


@pytest.mark.parametrize("name", _public())
def test_every_name_of_all_resolves_without_a_warning(name):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert getattr(stereovar, name) is not None


def test_version_is_a_string():
    assert isinstance(stereovar.__version__, str) and stereovar.__version__.count(".") >= 1


def test_dir_lists_all_sorted():
    assert dir(stereovar) == sorted(stereovar.__all__)
    assert len(set(stereovar.__all__)) == len(stereovar.__all__)


def test_deprecated_names_are_neither_in_all_nor_in_dir():
    for name in MITSUBA_ONLY:
        assert name not in stereovar.__all__
        assert name not in dir(stereovar)


@pytest.mark.parametrize("name", sorted(MITSUBA_ONLY))
def test_mitsuba_names_live_in_the_mitsuba_package(name):
    defined = getattr(importlib.import_module(MITSUBA_ONLY[name]), name)
    assert getattr(mitsuba, name) is defined
    assert name in mitsuba.__all__
    assert name in dir(mitsuba)


@pytest.mark.parametrize("name", sorted(MITSUBA_ONLY))
def test_deprecated_alias_warns_and_is_the_same_object(name):
    with pytest.warns(
        DeprecationWarning, match=rf"stereovar\.renderers\.mitsuba\.{name}\b"
    ) as record:
        obj = getattr(stereovar, name)
    assert obj is getattr(importlib.import_module(MITSUBA_ONLY[name]), name)
    assert record[0].filename == __file__, "the warning points at the caller's line"


def test_deprecated_alias_warns_on_from_import_too():
    with pytest.warns(DeprecationWarning, match="deprecated"):
        from stereovar import load_scene  # noqa: F401


def test_mitsuba_all_resolves():
    for name in mitsuba.__all__:
        assert getattr(mitsuba, name) is not None
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        mitsuba.nope  # noqa: B018


def _stub_imports() -> dict:
    """Name to module (relative, without the leading dot) of each import of the stub."""
    tree = ast.parse((PACKAGE / "__init__.pyi").read_text())
    out = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            assert node.level == 1, "the stub imports from stereovar's own modules"
            for alias in node.names:
                assert alias.asname == alias.name, f"{alias.name} must be re-exported as itself"
                out[alias.name] = node.module
    return out


def _stub_all() -> list:
    tree = ast.parse((PACKAGE / "__init__.pyi").read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and node.targets[0].id == "__all__":
            return ast.literal_eval(node.value)
    raise AssertionError("the stub has no __all__")


def test_stub_declares_exactly_the_public_names_from_their_modules():
    imports = _stub_imports()
    assert sorted(imports) == sorted(_public())
    assert _stub_all() == stereovar.__all__
    for name, module in imports.items():
        obj = getattr(importlib.import_module(f"stereovar.{module}"), name)
        assert obj is getattr(stereovar, name), name


def test_package_is_marked_typed():
    assert (PACKAGE / "py.typed").is_file()


def _source_files():
    """The package's Python files, outside ``__pycache__`` and private data folders (a name
    starting with one underscore, e.g. the workflow an installed wheel carries)."""
    return [
        p
        for p in PACKAGE.rglob("*.py")
        if not any(d.startswith("_") for d in p.relative_to(PACKAGE).parts[:-1])
    ]


def _python_folders():
    """Every folder under the package that holds a Python module at any depth."""
    folders = {p.parent for p in _source_files()}
    for folder in list(folders):
        folders.update(a for a in folder.parents if PACKAGE in (a, *a.parents))
    return sorted(folders)


def test_python_folders_are_found():
    found = {f.relative_to(PACKAGE).as_posix() for f in _python_folders()}
    assert {".", "statistics", "renderers/mitsuba"} <= found


@pytest.mark.parametrize(
    "folder", _python_folders(), ids=lambda f: f.relative_to(PACKAGE).as_posix()
)
def test_every_subpackage_has_a_documented_init_listing_its_modules(folder):
    init = folder / "__init__.py"
    assert init.is_file(), f"{folder} holds modules but has no __init__.py"
    doc = ast.get_docstring(ast.parse(init.read_text()))
    assert doc, f"{init} has no docstring"
    if folder == PACKAGE:
        return
    children = sorted(
        p.stem if p.suffix == ".py" else p.name
        for p in folder.iterdir()
        if (p.suffix == ".py" and p.stem != "__init__") or (p / "__init__.py").is_file()
    )
    missing = [c for c in children if f"{c}`" not in doc]
    assert not missing, f"the docstring of {init} does not name {missing}"


@pytest.mark.parametrize(
    "package",
    ["statistics", "io", "intervention", "figures", "scenes", "controls", "audit"],
)
def test_new_subpackages_import_none_of_their_modules(package):
    code = (
        "import json, sys\n"
        f"import stereovar.{package} as p\n"
        f"print(json.dumps(sorted(m for m in sys.modules if m.startswith('stereovar.{package}.'))))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) == []


def test_import_pulls_in_no_third_party_module():
    code = (
        "import json, sys\n"
        "before = set(sys.modules)\n"
        "import stereovar\n"
        "new = {m.split('.')[0] for m in set(sys.modules) - before}\n"
        "print(json.dumps(sorted(new - set(sys.stdlib_module_names) - {'stereovar'})))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) == []


def test_import_and_dir_pull_in_no_third_party_module():
    code = (
        "import json, sys\n"
        "import stereovar, stereovar.renderers.mitsuba as m\n"
        "dir(stereovar); dir(m); stereovar.__all__; m.__all__\n"
        "print(json.dumps(sorted({'numpy', 'drjit', 'mitsuba', 'xarray'} & set(sys.modules))))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) == []


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        stereovar.nope  # noqa: B018
