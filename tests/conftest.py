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


@pytest.fixture(scope="session")
def tiny_run(tmp_path_factory):
    """A copy of the workflow with the tiny config of ``tests/test_workflow.py``, run once to
    completion (``snakemake -j2 all``) and shared by every module that reads such a run;
    a test that changes it works on a copy (:func:`tiny_run_copy`)."""
    from .test_workflow import TINY, copy_workflow, snakemake

    root = copy_workflow(tmp_path_factory.mktemp("tiny") / "wf", TINY)
    snakemake(root, "-j2", "all")
    return root


@pytest.fixture(scope="session")
def tiny_run_copy(tiny_run):
    """A function of a folder: a copy of :func:`tiny_run` there, file times kept (so
    Snakemake finds every result up to date), to change freely."""
    import shutil

    def copy(root):
        return shutil.copytree(tiny_run, root, symlinks=True)

    return copy
