"""Backend selection: libLLVM discovery, DRJIT_LIBLLVM_PATH handling, variant choice.

Anything that sets environment variables read by Dr.Jit at import time, or that changes
Mitsuba's variant, runs in a subprocess so the test process is not affected.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from stereovar.errors import BackendError
from stereovar.renderers.mitsuba.backend import (
    MIN_LLVM_MAJOR,
    NO_LIBLLVM_SENTINEL,
    find_libllvm,
    libllvm_version,
)

REPO_ROOT = Path(__file__).resolve().parents[1]


def run_python(code: str, env_update: dict | None = None, unset=()) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter with ``src`` importable and a modified env."""
    env = dict(os.environ)
    for name in ("DRJIT_LIBLLVM_PATH", "STEREOVAR_LLVM_SEARCH_DIRS", *unset):
        env.pop(name, None)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(REPO_ROOT / "src"), *filter(None, [os.environ.get("PYTHONPATH")])]
    )
    env.update(env_update or {})
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


def touch(directory: Path, *names: str) -> None:
    directory.mkdir(parents=True, exist_ok=True)
    for name in names:
        (directory / name).write_bytes(b"")


def test_find_libllvm_picks_newest_supported(tmp_path):
    touch(tmp_path, "libLLVM-14.so", "libLLVM-15.so", "libLLVM.so.17", "libLLVM-19.so")
    assert find_libllvm([tmp_path]) == tmp_path / "libLLVM-19.so"


def test_find_libllvm_searches_every_directory(tmp_path):
    touch(tmp_path / "a", "libLLVM-17.so.1")
    touch(tmp_path / "b", "libLLVM.so.18.1", "libLLVMCore.a")
    assert find_libllvm([tmp_path / "missing", tmp_path / "a", tmp_path / "b"]) == (
        tmp_path / "b" / "libLLVM.so.18.1"
    )


def test_find_libllvm_ignores_old_versions(tmp_path):
    touch(tmp_path, "libLLVM-14.so", "libLLVM-15.so", "libLLVM-14.0.6.so.1", "libLLVM.so.15")
    assert find_libllvm([tmp_path]) is None


def test_find_libllvm_ignores_broken_links_and_unversioned_names(tmp_path):
    (tmp_path / "libLLVM-19.so").symlink_to(tmp_path / "gone.so")
    touch(tmp_path, "libLLVM.so")
    assert find_libllvm([tmp_path]) is None


def test_find_libllvm_reads_version_from_llvm_directory(tmp_path):
    touch(tmp_path / "llvm-18" / "lib", "libLLVM.so")
    touch(tmp_path / "llvm-15" / "lib", "libLLVM.so")
    dirs = [tmp_path / "llvm-15" / "lib", tmp_path / "llvm-18" / "lib"]
    assert find_libllvm(dirs) == tmp_path / "llvm-18" / "lib" / "libLLVM.so"


def test_find_libllvm_default_dirs_follow_override(tmp_path, monkeypatch):
    touch(tmp_path, "libLLVM-16.so")
    monkeypatch.setenv("STEREOVAR_LLVM_SEARCH_DIRS", str(tmp_path))
    assert find_libllvm() == tmp_path / "libLLVM-16.so"
    monkeypatch.setenv("STEREOVAR_LLVM_SEARCH_DIRS", str(tmp_path / "empty"))
    assert find_libllvm() is None


@pytest.mark.parametrize(
    ("name", "version"),
    [
        ("libLLVM-19.so", (19,)),
        ("libLLVM-19.1.so", (19, 1)),
        ("libLLVM.so.19.1", (19, 1)),
        ("libLLVM.so.19", (19,)),
        ("libLLVM-17.so.1", (17,)),
        ("libLLVM-14.0.6.so.1", (14, 0, 6)),
        ("libLLVM-19.dylib", (19,)),
        ("/usr/lib/llvm-19/lib/libLLVM.so", (19,)),
        ("/opt/homebrew/Cellar/llvm/19.1.7/lib/libLLVM.dylib", (19, 1, 7)),
        ("/data/2024/lib/libLLVM.so", None),
        ("libLLVMCore.a", None),
    ],
)
def test_libllvm_version_from_name(name, version):
    assert libllvm_version(name) == version


CONFIGURE = """
import json, os
from stereovar.renderers.mitsuba.backend import configure_llvm
from stereovar.errors import BackendError
try:
    path = configure_llvm()
except BackendError as err:
    print(json.dumps({"error": str(err)}))
else:
    print(json.dumps({"path": path and str(path), "env": os.environ.get("DRJIT_LIBLLVM_PATH")}))
"""


def configure(env_update) -> dict:
    result = run_python(CONFIGURE, env_update)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


def test_configure_llvm_sets_env_to_discovered_library(tmp_path):
    touch(tmp_path, "libLLVM-15.so", "libLLVM-19.so")
    out = configure({"STEREOVAR_LLVM_SEARCH_DIRS": str(tmp_path)})
    assert out == {"path": str(tmp_path / "libLLVM-19.so"), "env": str(tmp_path / "libLLVM-19.so")}


def test_configure_llvm_blocks_drjit_search_when_nothing_found(tmp_path):
    out = configure({"STEREOVAR_LLVM_SEARCH_DIRS": str(tmp_path)})
    assert out == {"path": None, "env": NO_LIBLLVM_SENTINEL}


def test_configure_llvm_respects_user_path(tmp_path):
    touch(tmp_path, "libLLVM-19.so")
    user = "/somewhere/else/libLLVM-18.so"
    out = configure({"STEREOVAR_LLVM_SEARCH_DIRS": str(tmp_path), "DRJIT_LIBLLVM_PATH": user})
    assert out == {"path": user, "env": user}


def test_configure_llvm_rediscovers_when_env_holds_sentinel(tmp_path):
    touch(tmp_path, "libLLVM-19.so")
    out = configure(
        {"STEREOVAR_LLVM_SEARCH_DIRS": str(tmp_path), "DRJIT_LIBLLVM_PATH": NO_LIBLLVM_SENTINEL}
    )
    assert out["path"] == str(tmp_path / "libLLVM-19.so")


def test_configure_llvm_rejects_user_path_older_than_16():
    out = configure({"DRJIT_LIBLLVM_PATH": "/usr/lib/x86_64-linux-gnu/libLLVM-15.so"})
    message = out["error"]
    assert "\n" not in message
    assert "libLLVM 15" in message and "libllvm19" in message and "DRJIT_LIBLLVM_PATH" in message


def test_importing_the_package_loads_no_heavy_module():
    code = """
    import importlib, json, pkgutil, sys
    import stereovar.renderers.mitsuba.backend
    light = "numpy" not in sys.modules
    import stereovar
    for info in pkgutil.walk_packages(stereovar.__path__, "stereovar."):
        if not info.name.endswith("__main__"):
            importlib.import_module(info.name)
    heavy = sorted(m for m in ("drjit", "mitsuba") if m in sys.modules)
    print(json.dumps({"backend_without_numpy": light, "heavy": heavy}))
    """
    result = run_python(code)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout) == {"backend_without_numpy": True, "heavy": []}, (
        "stereovar modules must import mitsuba/drjit only through "
        "stereovar.renderers.mitsuba.backend.load_mitsuba"
    )


VARIANT = """
import json
from stereovar.renderers.mitsuba import backend
from stereovar.errors import BackendError
out = {}
try:
    out["variant"] = backend.select_variant(REQUESTED)
except BackendError as err:
    out["error"] = str(err)
out["available"] = backend.available_variants()
import drjit as dr  # already imported (and configured) by stereovar.renderers.mitsuba.backend
out["cuda"] = bool(dr.has_backend(dr.JitBackend.CUDA))
print(json.dumps(out))
"""


def select_in_subprocess(requested="auto", env_update=None):
    result = run_python(VARIANT.replace("REQUESTED", repr(requested)), env_update)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout), result.stderr


def _need_llvm():
    if find_libllvm() is None and not os.environ.get("DRJIT_LIBLLVM_PATH"):
        message = f"no libLLVM >= {MIN_LLVM_MAJOR} on this machine; run scripts/setup.sh"
        if os.environ.get("STEREOVAR_ALLOW_SCALAR") == "1":
            pytest.skip(message + " (STEREOVAR_ALLOW_SCALAR=1)")
        pytest.fail(message)


def test_auto_picks_gpu_else_llvm():
    _need_llvm()
    out, _ = select_in_subprocess("auto")
    assert out["variant"] == ("cuda_ad_rgb" if out["cuda"] else "llvm_ad_rgb")
    assert out["available"][-2:] == ["llvm_ad_rgb", "scalar_rgb"]


def test_auto_falls_back_to_scalar_with_one_line_warning(tmp_path):
    out, stderr = select_in_subprocess("auto", {"STEREOVAR_LLVM_SEARCH_DIRS": str(tmp_path)})
    if out["cuda"]:
        pytest.skip("a CUDA GPU is usable here, so auto never falls back to scalar")
    assert out["variant"] == "scalar_rgb"
    assert out["available"] == ["scalar_rgb"]
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1, stderr
    assert "BackendWarning" in lines[0] and "scalar_rgb" in lines[0]
    assert "sudo apt-get install libllvm19" in lines[0] and "DRJIT_LIBLLVM_PATH" in lines[0]


def test_forced_llvm_without_libllvm_raises_one_line_error(tmp_path):
    out, _ = select_in_subprocess("llvm_ad_rgb", {"STEREOVAR_LLVM_SEARCH_DIRS": str(tmp_path)})
    message = out["error"]
    assert "\n" not in message
    assert "'llvm_ad_rgb' is not available" in message
    assert "libllvm19" in message and "available here: scalar_rgb" in message


def test_forced_unknown_variant_lists_known_ones():
    out, _ = select_in_subprocess("llvm_rgb_typo")
    assert "\n" not in out["error"]
    assert "unknown Mitsuba variant 'llvm_rgb_typo'" in out["error"]
    assert "scalar_rgb" in out["error"]


def test_forced_cuda_without_gpu_raises_one_line_error():
    from stereovar.renderers.mitsuba.backend import available_variants, select_variant

    if "cuda_ad_rgb" in available_variants():
        pytest.skip("a CUDA GPU is usable here")
    with pytest.raises(BackendError) as info:
        select_variant("cuda_ad_rgb")
    message = str(info.value)
    assert "\n" not in message
    assert "'cuda_ad_rgb' is not available" in message and "CUDA" in message
    assert "available here:" in message and "scalar_rgb" in message


def test_load_mitsuba_caches_and_switches_variants():
    code = """
    import json
    from stereovar.renderers.mitsuba.backend import describe_backend, load_mitsuba, select_variant
    auto = select_variant()
    first = load_mitsuba("scalar_rgb").variant()
    second = load_mitsuba().variant()
    again = load_mitsuba("scalar_rgb")
    print(json.dumps({"auto": auto, "seen": [first, second, again.variant()],
                      "info": describe_backend()}))
    """
    result = run_python(code)
    assert result.returncode == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["seen"] == ["scalar_rgb", out["auto"], "scalar_rgb"]
    info = out["info"]
    assert set(info) == {"variant", "libllvm", "jit_target", "mitsuba_version", "drjit_version"}
    assert info["variant"] == "scalar_rgb" and info["jit_target"] == ""
    assert info["mitsuba_version"] and info["drjit_version"]


RENDER_TWICE = """
import json, sys
import numpy as np
from stereovar.errors import BackendError
from stereovar.renderers.mitsuba.backend import describe_backend, load_mitsuba
try:
    mi = load_mitsuba("llvm_ad_rgb")
except BackendError as err:
    print(json.dumps({"error": str(err)}))
    sys.exit(0)
scene = mi.load_dict(mi.cornell_box())
image = np.array(mi.render(scene, spp=4, seed=1), dtype=np.float32)
np.save(sys.argv[1], image)
print(json.dumps({"target": describe_backend()["jit_target"]}))
"""


def _render_with_target(tmp_path, target):
    out = tmp_path / f"{target}.npy"
    env = dict(os.environ, STEREOVAR_JIT_TARGET=target)
    env["PYTHONPATH"] = str(REPO_ROOT / "src")
    proc = subprocess.run(
        [sys.executable, "-c", RENDER_TWICE, str(out)], env=env, capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1]), out


def test_jit_target_compiles_for_another_cpu_or_is_refused(tmp_path):
    """``STEREOVAR_JIT_TARGET=avx2-w4`` compiles the LLVM kernels for a generic AVX2 CPU with
    4 lanes, recorded in the provenance: its renders differ from the host's in the last bits
    and agree in the mean to float32 precision. A CPU without AVX2 refuses the target in one
    line instead of crashing in its kernels."""
    import numpy as np

    from stereovar.renderers.mitsuba.jit_target import PRESETS, missing_cpu_flags

    host, host_file = _render_with_target(tmp_path, "host")
    other, other_file = _render_with_target(tmp_path, "avx2-w4")
    if "error" in host:  # no LLVM back end here: the target cannot be applied either
        assert "error" in other
        return
    if missing_cpu_flags(PRESETS["avx2-w4"][1]):
        assert "which this CPU lacks" in other["error"] and "\n" not in other["error"]
        return
    cpu, width = host["target"].split("/")
    assert cpu and int(width) in (4, 8, 16)
    assert other["target"] == "x86-64-v3/4"
    a = np.load(host_file).astype(np.float64)
    b = np.load(other_file).astype(np.float64)
    assert (a != b).any()  # the kernels really were compiled differently
    # the mean over 256x256x4 samples: float32 rounding, not Monte Carlo noise
    assert abs(a.mean() - b.mean()) <= 1e-5 * a.mean()


def test_jit_target_values_are_read_or_refused_in_one_line():
    from stereovar.renderers.mitsuba.jit_target import missing_cpu_flags, parse_jit_target

    assert parse_jit_target("") is None
    assert parse_jit_target(" host ") is None
    assert parse_jit_target("skylake-avx512:+avx512f:16") == ("skylake-avx512", "+avx512f", 16)
    for bad in ("avx3", "haswell:+avx2", "haswell:+avx2:5", ":+avx2:8", "haswell:+avx2:x"):
        with pytest.raises(BackendError) as info:
            parse_jit_target(bad)
        assert "\n" not in str(info.value) and "CPU:FEATURES:WIDTH" in str(info.value)
    cpuinfo = "processor : 0\nflags : fpu sse4_1 sse4_2 avx avx2 fma bmi1 abm\n"
    assert missing_cpu_flags("+avx2,+fma,+sse4.2,+bmi,+lzcnt", cpuinfo) == []
    assert missing_cpu_flags("+avx2,+avx512f,-avx512vl", cpuinfo) == ["avx512f"]


def test_a_target_this_cpu_cannot_run_is_refused_before_any_kernel():
    result = run_python(
        """
        from stereovar.renderers.mitsuba.backend import load_mitsuba
        load_mitsuba("auto")
        """,
        {"STEREOVAR_JIT_TARGET": "x86-64-v3:+avx2,+stereovar-no-such-feature:8"},
    )
    assert result.returncode != 0
    last = result.stderr.strip().splitlines()[-1]
    assert "stereovar-no-such-feature, which this CPU lacks" in last
