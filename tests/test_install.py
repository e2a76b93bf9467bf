"""stereovar as a data team installs it: a wheel in a new virtual environment, run from an
empty directory, and the conda environment that cluster jobs (--sdm conda) get.

The new environment gets the wheel without its dependencies; those come from the test's own
environment through a ``.pth`` file, so that the test needs no network and no second copy of
Mitsuba and PyTorch. A ``.pth`` file's directories are not scanned for further ``.pth``
files, so the checkout's editable install does not leak into it: the test asserts that
``stereovar`` is imported from the wheel.
"""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.workflow


def run(cmd, cwd, env=None, check=True):
    proc = subprocess.run(
        [str(c) for c in cmd], cwd=cwd, env=env, capture_output=True, text=True, check=False
    )
    if check and proc.returncode != 0:
        raise AssertionError(f"{cmd} failed:\n{proc.stdout}\n{proc.stderr}")
    return proc


def new_environment(folder: Path) -> Path:
    """A new virtual environment at ``folder`` whose dependencies come from this one; returns
    its Python."""
    run([sys.executable, "-m", "venv", folder], cwd=folder.parent)
    python = folder / "bin" / "python"
    purelib = run([python, "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                  cwd=folder).stdout.strip()  # fmt: skip
    Path(purelib, "_dependencies.pth").write_text(sysconfig.get_path("purelib") + "\n")
    return python


def clean_env(python: Path) -> dict:
    """This process's environment with the new environment's bin first and nothing that
    points at the checkout."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = f"{python.parent}{os.pathsep}{env.get('PATH', '')}"
    env["PIP_NO_BUILD_ISOLATION"] = "0"  # build backends from the environment: no network
    env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"
    return env


#: Folders of the checkout that a test run itself writes (or that are not the project's).
SKIP = (".git", ".venv", "__pycache__", ".pytest_cache", ".ruff_cache")


def checkout_state() -> dict:
    """Every path of the checkout (:data:`SKIP` aside) with its mtime and size."""
    out = {}
    for folder, dirs, files in os.walk(REPO):
        dirs[:] = [d for d in dirs if d not in SKIP]
        for name in dirs + files:
            st = Path(folder, name).lstat()
            out[str(Path(folder, name).relative_to(REPO))] = (st.st_mtime_ns, st.st_size)
    return out


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("dist")
    run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "-w", out, REPO], cwd=out)  # fmt: skip
    (path,) = out.glob("stereovar-*.whl")
    return path


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory) -> Path:
    """The Python of a new environment with the wheel installed."""
    python = new_environment(tmp_path_factory.mktemp("venv") / "env")
    run([python, "-m", "pip", "install", "-q", "--no-deps", "--no-index", wheel],
        cwd=wheel.parent, env=clean_env(python))  # fmt: skip
    return python


def test_the_wheel_carries_the_workflow_as_the_checkout_lays_it_out(wheel):
    import zipfile

    names = set(zipfile.ZipFile(wheel).namelist())
    tracked = run(["git", "ls-files", "Snakefile", "config.yaml", "workflow", "envs",
                   "profiles"], cwd=REPO).stdout.split()  # fmt: skip
    assert tracked
    missing = [f for f in tracked if f"stereovar/_workflow/{f}" not in names]
    assert not missing, f"not in the wheel: {missing}"
    schemas = {p.relative_to(REPO / "src").as_posix() for p in (REPO / "src").rglob("*.yaml")}
    assert schemas and schemas <= names


def test_installed_stereovar_says_its_version_and_runs_its_own_workflow(installed, tmp_path):
    env = clean_env(installed)
    where = run([installed, "-c", "import stereovar; print(stereovar.__file__)"], tmp_path, env)
    package = Path(where.stdout.strip()).parent
    assert package.is_relative_to(installed.parent.parent), where.stdout
    version = run([installed.parent / "stereovar", "--version"], tmp_path, env).stdout
    import stereovar

    assert version.split()[:2] == ["stereovar", stereovar.__version__]
    assert str(package / "_workflow") in version


def test_init_writes_starter_configs_and_an_example_that_reads_its_files(installed, tmp_path):
    env = clean_env(installed)
    cli = installed.parent / "stereovar"
    out = run([cli, "init", "--example"], tmp_path, env).stdout
    config = yaml.safe_load((tmp_path / "audit.yaml").read_text())["audit"]
    for frame in ("f00", "f01"):
        assert (tmp_path / config["disparity"].format(frame=frame)).is_file()
        for view in config["views"].values():
            assert (
                tmp_path / config["renders"].format(frame=frame, view=view, seed="000")
            ).is_file()
    package = installed.parent.parent
    (shipped,) = package.glob("lib/python*/site-packages/stereovar/_workflow/config.yaml")
    assert (tmp_path / "config.yaml").read_text() == shipped.read_text()
    again = run([cli, "init"], tmp_path, env).stdout  # kept, never overwritten
    assert again.count("kept") == 2 and "wrote" in out
    # the default run plans from here: the workflow's rules, the scenes generated here
    plan = run([cli, "run", "-j1", "--", "-n"], tmp_path, env).stdout
    assert "generate_scene" in plan


def test_audit_in_an_empty_directory_writes_the_verdict_page_there(installed, tmp_path):
    """From ``pip install`` of the wheel to a verdict page, in a directory that holds only the
    renders the test writes, without touching the checkout."""
    before = checkout_state()
    env = clean_env(installed)
    write = (
        "import yaml; from stereovar.audit.synthetic import write_synthetic_audit as w; "
        "s, _ = w('data', n_frames=1, width=64, height=48, n_seeds=4); "
        "yaml.safe_dump({'audit': s}, open('audit.yaml', 'w'))"
    )
    run([installed, "-c", write], tmp_path, env)
    out = run([installed.parent / "stereovar", "audit", "audit.yaml"], tmp_path, env).stdout
    page = tmp_path / "results" / "audit" / "synthetic" / "verdict.html"
    assert page.is_file() and f"verdict page: {page}" in out
    assert "intensity-controlled rho" in out
    assert checkout_state() == before


def test_run_refuses_an_unknown_preset_and_options_after_dashes_elsewhere(installed, tmp_path):
    env = clean_env(installed)
    cli = installed.parent / "stereovar"
    proc = run([cli, "run", "--preset", "papr"], tmp_path, env, check=False)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "paper" in proc.stderr and "probe" in proc.stderr
    proc = run([cli, "init", "--", "-n"], tmp_path, env, check=False)
    assert proc.returncode == 2 and "after --" in proc.stderr
    assert not any(tmp_path.iterdir())


# --- the conda environment of --sdm conda jobs -------------------------------------------


def test_conda_post_deploy_script_installs_the_running_stereovar(tmp_path):
    """Snakemake runs ``envs/stereovar.post-deploy.sh`` in a new job environment; with the
    requirement the Snakefile exports (this checkout), ``import stereovar`` works there."""
    from stereovar.workflow_home import REQUIREMENT_ENV, install_requirement

    script = REPO / "envs" / "stereovar.post-deploy.sh"
    assert script.with_name("stereovar.yaml").is_file()  # Snakemake pairs them by name
    python = new_environment(tmp_path / "job_env")
    env = clean_env(python)
    requirement = install_requirement()
    assert Path(requirement) == REPO  # the checkout, installed editable here
    missing = run(["bash", script], tmp_path, env, check=False)
    assert missing.returncode == 1 and REQUIREMENT_ENV in missing.stderr
    env[REQUIREMENT_ENV] = requirement
    out = run(["bash", script], tmp_path, env).stdout
    import stereovar

    assert f"stereovar {stereovar.__version__} installed" in out
    where = run([python, "-c", "import stereovar; print(stereovar.__file__)"], tmp_path, env)
    assert Path(where.stdout.strip()).is_relative_to(python.parent.parent)
