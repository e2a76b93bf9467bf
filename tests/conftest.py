"""Shared fixtures."""

import pytest


@pytest.fixture(scope="session")
def mi():
    """Mitsuba with the automatically selected variant (LLVM on CI machines)."""
    from stereovar.renderers.mitsuba.backend import load_mitsuba

    return load_mitsuba("auto")


@pytest.fixture
def tree_snapshot():
    """A function of a folder: every path under it (``.snakemake`` aside) with its mtime and,
    for a file, the SHA-256 of its bytes; equal snapshots mean nothing was written there."""
    import hashlib
    import os
    from pathlib import Path

    def snapshot(root) -> dict:
        out = {}
        for folder, dirs, files in os.walk(root):
            dirs[:] = [d for d in dirs if d != ".snakemake"]
            for name in dirs + files:
                path = Path(folder, name)
                st = path.lstat()
                digest = (
                    hashlib.sha256(path.read_bytes()).hexdigest()
                    if path.is_file() and not path.is_symlink()
                    else None
                )
                out[str(path.relative_to(root))] = (st.st_mtime_ns, digest)
        return out

    return snapshot
