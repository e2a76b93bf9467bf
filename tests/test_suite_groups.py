"""`make test`'s two xdist workers keep a module's tests together and the tests of the shared
tiny run together (tests/conftest.py), so each module-scoped or session-scoped run is made
once and a test that changes the shared run and puts it back is never seen half-way."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent

MODULE = """
import pytest

@pytest.fixture(scope="session")
def tiny_run():
    return "stand-in for the shared tiny run"

@pytest.mark.parametrize("i", range(4))
def test_own(i):
    pass

@pytest.mark.parametrize("i", range(3))
def test_shared(tiny_run, i):
    pass
"""


def test_modules_and_the_shared_run_each_stay_on_one_worker(tmp_path):
    pytest.importorskip("xdist", reason="the test extra (pytest-xdist) is not installed")
    shutil.copy(HERE / "conftest.py", tmp_path / "conftest.py")
    for name in ("alpha", "beta", "gamma"):
        (tmp_path / f"test_{name}.py").write_text(MODULE)
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-n", "2", "--dist", "loadgroup", "-v",
         "-p", "no:cacheprovider", str(tmp_path)],
        cwd=tmp_path, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    workers: dict[str, set[str]] = defaultdict(set)
    ran = 0
    for line in proc.stdout.splitlines():
        m = re.match(r"\[(gw\d+)\] .*PASSED (test_\w+)\.py::(test_\w+)\[\d+\]@(\w+)", line)
        if m:
            worker, module, test, group = m.groups()
            ran += 1
            expected = "tiny_run" if test == "test_shared" else module
            assert group == expected, line
            workers[group].add(worker)
    assert ran == 3 * 7, proc.stdout[-3000:]
    assert set(workers) == {"tiny_run", "test_alpha", "test_beta", "test_gamma"}
    assert all(len(w) == 1 for w in workers.values()), dict(workers)
    # two workers did run: the grouping is not one worker doing everything
    assert len(set.union(*workers.values())) == 2, dict(workers)
