"""The lazy notebook API: every listed name resolves, and the import itself stays cheap."""

import subprocess
import sys

import pytest

import stereovar


@pytest.mark.parametrize("name", sorted(stereovar._API))
def test_every_public_name_resolves_to_its_module(name):
    import importlib

    obj = getattr(stereovar, name)
    assert getattr(importlib.import_module(f"stereovar.{stereovar._API[name]}"), name) is obj


def test_import_pulls_in_no_third_party_module():
    code = "import sys, stereovar; print(sorted({'numpy', 'drjit', 'mitsuba'} & set(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        stereovar.nope  # noqa: B018
