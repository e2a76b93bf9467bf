"""Shared fixtures."""

import pytest


@pytest.fixture(scope="session")
def mi():
    """Mitsuba with the automatically selected variant (LLVM on CI machines)."""
    from stereovar.renderers.mitsuba.backend import load_mitsuba

    return load_mitsuba("auto")
