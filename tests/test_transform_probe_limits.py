"""Inputs past what the camera model, the store transforms and the learned probe can hold, and
the conda post-deploy script's requirement: each is refused in one line naming the setting
and the fix, or handled by a documented law, never run as code, never left to hang."""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
POST_DEPLOY = REPO / "envs" / "stereovar.post-deploy.sh"


# --- the conda post-deploy script ------------------------------------------------------------


def _post_deploy(tmp_path, requirement) -> subprocess.CompletedProcess:
    """Run the post-deploy script with ``requirement``; ``python -m pip`` is a stub that
    installs nothing, every other ``python`` call is this interpreter (stereovar installed)."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir(exist_ok=True)
    stub = bin_dir / "python"
    stub.write_text(
        "#!/bin/sh\n"
        'if [ "$1" = "-m" ] && [ "$2" = "pip" ]; then exit 0; fi\n'
        f'exec {shlex.quote(sys.executable)} "$@"\n'
    )
    stub.chmod(0o755)
    env = {
        "PATH": f"{bin_dir}{os.pathsep}/usr/bin{os.pathsep}/bin",
        "HOME": str(tmp_path),
        "STEREOVAR_REQUIREMENT": requirement,
    }
    return subprocess.run(
        ["bash", str(POST_DEPLOY)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )


def test_post_deploy_never_runs_the_requirement_as_python(tmp_path):
    requirement = '/srv/x{__import__("os").system("id > INJECTED")}y'
    proc = _post_deploy(tmp_path, requirement)
    assert not (tmp_path / "INJECTED").exists()
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.endswith(f"installed from {requirement}\n")


def test_post_deploy_takes_a_checkout_path_with_a_quote(tmp_path):
    requirement = "/home/o'brien/stereovar"
    proc = _post_deploy(tmp_path, requirement)
    assert proc.returncode == 0, proc.stderr
    import stereovar

    assert proc.stdout == f"stereovar {stereovar.__version__} installed from {requirement}\n"
