"""Every Examples section of the library runs as a doctest."""

import doctest
import importlib
import pkgutil

import pytest

import stereovar

MODULES = sorted(m.name for m in pkgutil.walk_packages(stereovar.__path__, "stereovar."))


@pytest.mark.parametrize("name", MODULES)
def test_examples_run(name):
    module = importlib.import_module(name)
    result = doctest.testmod(
        module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, verbose=False
    )
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {name}"
