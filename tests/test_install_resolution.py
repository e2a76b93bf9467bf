"""The README's installed-tool line pulls no CUDA package.

The ``pip install`` line is read from README.md as written (its shell continuation joined,
its comment dropped) and resolved by ``pip install --dry-run --ignore-installed --report``
against the package index, with the wheel it names built from this checkout. On Linux,
PyPI's torch is the CUDA build, whose ``nvidia-*`` dependencies come to about 2.7 GB; the
line avoids them by naming PyTorch's CPU wheel index, where ``2.13.0+cpu`` satisfies the
``probe`` extra's pin and pip prefers it to PyPI's ``2.13.0``.

pip runs with ``--isolated``, every ``PIP_*`` variable cleared and ``PIP_CONFIG_FILE``
set to ``os.devnull`` (no configuration file at all): a development machine's find-links
folder, local mirrors or constraints may hold a CPU torch and would hide a CUDA resolution.
Only the TLS certificate bundle is carried over, which chooses no package.

Where PyTorch's CPU index cannot be reached, the test substitutes a local PEP 503 simple
index for it, at the same option of the same line, holding only the file that index serves
for this interpreter: ``torch-<pin>+cpu-<tags>.whl``, found in the find-links folders of
pip's configuration. The CPU index also serves other projects (numpy, jinja2, ...), all of
them CPU-only; the substitute holds torch alone, since which torch build pip picks is the
question. The test skips where PyPI cannot be reached, or where neither the CPU index nor a
copy of its wheel is at hand.

``make docs`` installs the ``docs`` extra alone (``scripts/setup.sh --docs``); resolved the
same way, it brings Sphinx at its pins and stereovar's own dependencies, and no Blender, no
PyTorch, no pyoidn and no CUDA package.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shlex
import shutil
import socket
import subprocess
import sys
from pathlib import Path
from urllib.parse import quote, urlsplit

import pytest

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"

#: Packages of a CUDA build of PyTorch: NVIDIA's libraries, CUDA's Python bindings, Triton.
CUDA_PACKAGE = re.compile(r"^(nvidia-|cuda-|triton$)")


def readme_install_line(text: str) -> list[str]:
    r"""The arguments of the README's ``pip install`` line of the installed tool (the one that
    installs a wheel from ``dist/``), its continuation lines joined and comments dropped.

    Examples
    --------
    >>> readme_install_line('pip install "dist/a.whl[x]" \\\n  --extra-index-url U  # c\n')
    ['pip', 'install', 'dist/a.whl[x]', '--extra-index-url', 'U']
    """
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if not line.startswith("pip install") or "dist/" not in line:
            continue
        command = ""
        for part in lines[i:]:
            part = part.split("  #")[0].rstrip()
            if part.endswith("\\"):
                command += part[:-1] + " "
                continue
            command += part
            break
        return shlex.split(command)
    raise AssertionError("README.md has no `pip install dist/...whl` line")


def probe_pin() -> str:
    """The exact torch version of the ``probe`` extra in pyproject.toml."""
    text = (REPO / "pyproject.toml").read_text(encoding="utf-8")
    match = re.search(r'^probe = \["torch==([\w.]+)"\]$', text, re.M)
    assert match, "the probe extra pins torch exactly: probe = [\"torch==X.Y.Z\"]"
    return match[1]


def reachable(host: str, port: int = 443, timeout: float = 5.0) -> bool:
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError:
        return False
    return True


def pip_settings() -> dict[str, list[str]]:
    """pip's settings as this environment configures them (files and ``PIP_*``), by key."""
    out = subprocess.run(
        [sys.executable, "-m", "pip", "config", "list"], capture_output=True, text=True
    ).stdout
    settings: dict[str, list[str]] = {}
    for line in out.splitlines():
        key, _, value = line.partition("=")
        settings.setdefault(key.rsplit(".", 1)[-1], []).append(value.strip("'\""))
    return settings


def cpu_wheel(version: str, folders: list[str]) -> Path | None:
    """A wheel ``torch-<version>+cpu`` for this interpreter in one of ``folders``."""
    from packaging.tags import sys_tags
    from packaging.utils import parse_wheel_filename

    supported = set(sys_tags())
    for folder in folders:
        path = Path(urlsplit(folder).path if folder.startswith("file:") else folder)
        for wheel in sorted(path.glob(f"torch-{version}+cpu-*.whl")) if path.is_dir() else []:
            if parse_wheel_filename(wheel.name)[3] & supported:
                return wheel
    return None


def simple_index(root: Path, wheel: Path) -> str:
    """A PEP 503 simple index at ``root`` serving ``wheel`` alone; returns its URL."""
    project = root / "torch"
    project.mkdir(parents=True)
    digest = hashlib.sha256(wheel.read_bytes()).hexdigest()
    (project / wheel.name).symlink_to(wheel)
    (project / "index.html").write_text(
        f'<!DOCTYPE html><html><body><a href="{quote(wheel.name)}#sha256={digest}">'
        f"{wheel.name}</a></body></html>\n"
    )
    return root.as_uri()


def isolated_env() -> dict[str, str]:
    """This environment without any ``PIP_*`` variable, and no pip configuration file."""
    env = {k: v for k, v in os.environ.items() if not k.upper().startswith("PIP_")}
    env["PIP_CONFIG_FILE"] = os.devnull
    return env


def resolve(args: list[str], cwd: Path) -> list[dict]:
    """The packages ``pip install ARGS`` would install into an empty environment."""
    settings = pip_settings()
    cert = (settings.get("cert") or [None])[0] or os.environ.get("SSL_CERT_FILE")
    report = cwd / "report.json"
    cmd = [sys.executable, "-m", "pip", "--isolated", *args[1:], "--dry-run",
           "--ignore-installed", "--quiet", "--disable-pip-version-check",
           "--report", str(report)]  # fmt: skip
    if cert:
        cmd += ["--cert", cert]
    proc = subprocess.run(
        cmd, cwd=cwd, env=isolated_env(), capture_output=True, text=True, timeout=600
    )
    assert proc.returncode == 0, f"{shlex.join(cmd)} failed:\n{proc.stdout}\n{proc.stderr}"
    return json.loads(report.read_text())["install"]


@pytest.fixture(scope="module")
def checkout_wheel(tmp_path_factory) -> Path:
    """This checkout built as a wheel, once for the module."""
    if not reachable("pypi.org"):
        pytest.skip("PyPI cannot be reached from here")
    dist = tmp_path_factory.mktemp("dist")
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "-w", dist, REPO], check=True, capture_output=True,
    )  # fmt: skip
    (wheel,) = dist.glob("stereovar-*.whl")
    return wheel


def in_work_folder(wheel: Path, work: Path) -> Path:
    """``work/dist/<wheel>``, the wheel as the README's line names it."""
    (work / "dist").mkdir()
    return Path(shutil.copy(wheel, work / "dist" / wheel.name))


@pytest.fixture(scope="module")
def resolution(checkout_wheel, tmp_path_factory) -> tuple[list[str], list[dict]]:
    """The README's line as run (the CPU index substituted where unreachable) and what it
    would install."""
    line = readme_install_line(README.read_text(encoding="utf-8"))
    assert line[:2] == ["pip", "install"], line
    work = tmp_path_factory.mktemp("resolve")
    (target,) = [a for a in line if a.startswith("dist/")]
    in_work_folder(checkout_wheel, work)
    built = [p.name for p in (work / "dist").glob("stereovar-*.whl")]
    assert built == [Path(target.split("[")[0]).name], f"README names {target}, built {built}"
    args = list(line)
    for i, arg in enumerate(args):
        host = urlsplit(arg).hostname
        if host and not reachable(host):
            folders = pip_settings().get("find-links", [])
            folders = [f for value in folders for f in value.split()]
            wheel = cpu_wheel(probe_pin(), folders)
            if wheel is None:
                pytest.skip(f"{host} cannot be reached and no torch +cpu wheel is at hand")
            args[i] = simple_index(work / "cpu-index", wheel)
    return args, resolve(args, work)


def test_readme_install_line_pulls_no_cuda_package(resolution):
    args, installed = resolution
    names = {item["metadata"]["name"].lower().replace("_", "-"): item for item in installed}
    import stereovar

    assert names["stereovar"]["metadata"]["version"] == stereovar.__version__
    # the probe extra was resolved: its torch, at the pinned release
    torch = names["torch"]["metadata"]["version"]
    assert torch.split("+")[0] == probe_pin(), torch
    assert "pyoidn" in names, "the mitigations extra was not resolved"
    cuda = sorted(n for n in names if CUDA_PACKAGE.match(n))
    assert not cuda, (
        f"{shlex.join(args)} would install torch {torch} with {len(cuda)} CUDA packages: "
        f"{', '.join(cuda)}"
    )


# --- make docs: the docs extra alone --------------------------------------------------------

#: What the docs extra must not bring: Blender, PyTorch (with CUDA's packages), OIDN.
NOT_FOR_DOCS = re.compile(r"^(bpy|torch|pyoidn|nvidia-.*|cuda-.*|triton)$")


def docs_extra() -> dict[str, str]:
    """The ``docs`` extra of pyproject.toml: each package's exact pin, by name."""
    tomllib = pytest.importorskip("tomllib", reason="reading pyproject.toml needs Python 3.11")
    with open(REPO / "pyproject.toml", "rb") as f:
        extra = tomllib.load(f)["project"]["optional-dependencies"]["docs"]
    pins = {}
    for requirement in extra:
        name, _, version = requirement.partition("==")
        assert version, f"{requirement}: the docs extra pins each package exactly"
        pins[name.strip().lower()] = version.strip()
    return pins


@pytest.fixture(scope="module")
def docs_resolution(checkout_wheel, tmp_path_factory) -> list[dict]:
    """What ``pip install <wheel>[docs]`` would install into an empty environment."""
    work = tmp_path_factory.mktemp("resolve-docs")
    wheel = in_work_folder(checkout_wheel, work)
    return resolve(["pip", "install", f"dist/{wheel.name}[docs]"], work)


def test_the_docs_extra_brings_sphinx_and_no_blender_pytorch_or_cuda(docs_resolution):
    names = {
        item["metadata"]["name"].lower().replace("_", "-"): item["metadata"]["version"]
        for item in docs_resolution
    }
    pins = docs_extra()
    assert "sphinx" in pins and len(pins) >= 4, pins
    for name, version in pins.items():
        assert names.get(name) == version, f"{name}: {names.get(name)}, the extra pins {version}"
    assert "mitsuba" in names and "snakemake" in names, "stereovar's own dependencies"
    unwanted = sorted(n for n in names if NOT_FOR_DOCS.match(n))
    assert not unwanted, f"the docs extra would install {', '.join(unwanted)}"
