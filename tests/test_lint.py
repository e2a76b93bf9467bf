"""Static checks: ruff on the whole repository and `snakemake --lint` on the workflow."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", *args],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_ruff_is_clean():
    result = run("ruff", "check", "--no-cache", ".")
    assert result.returncode == 0, f"ruff check found problems:\n{result.stdout}{result.stderr}"


def test_snakemake_lint_is_clean():
    if not (REPO_ROOT / "Snakefile").is_file():
        pytest.fail(f"no Snakefile in {REPO_ROOT}; the workflow must exist for `snakemake --lint`")
    result = run("snakemake", "--lint")
    output = result.stdout + result.stderr
    assert result.returncode == 0, f"snakemake --lint failed:\n{output}"
    assert "Lints for" not in output, f"snakemake --lint reported lints:\n{output}"
