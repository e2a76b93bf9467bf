"""The CPU that Dr.Jit's LLVM back end compiles kernels for, and a way to choose another.

Dr.Jit compiles every kernel for the host CPU: its vector width (4, 8 or 16 lanes), its
instruction set and LLVM's FMA contraction differ between CPUs, so float32 renders and the
ground truth differ in their last bits from one machine to the next. Results compared
across machines therefore need tolerances; ``STEREOVAR_JIT_TARGET`` lets one machine compile
as another would, so a test suite or a golden file can be checked against a second target
before it meets a second CPU.

Environment variables
---------------------
STEREOVAR_JIT_TARGET
    ``host`` (the default: Dr.Jit's own choice), a name from :data:`PRESETS` (``avx2``:
    a generic AVX2 + FMA x86-64 CPU with 8 lanes, the common denominator of current x86
    servers; ``avx2-w4``: the same instructions on 4 lanes), or ``CPU:FEATURES:WIDTH`` in
    LLVM's terms (e.g. ``haswell:+avx,+avx2,+fma:8``). A target that needs an instruction
    this CPU lacks is refused: its kernels would stop the process with SIGILL.

Dr.Jit 1.x does not expose ``jit_llvm_set_target`` to Python; :func:`apply_jit_target` calls
it in ``libdrjit-core`` through :mod:`ctypes`, after the LLVM back end has started (which
sets the host's target) and before any kernel is compiled. Dr.Jit's kernel cache is keyed
by the target, so kernels of two targets never mix.
"""

from __future__ import annotations

import ctypes
import os
import sys
from pathlib import Path

from stereovar.errors import BackendError

__all__ = ["ENV", "PRESETS", "apply_jit_target", "current_jit_target", "parse_jit_target"]

ENV = "STEREOVAR_JIT_TARGET"

_AVX2 = "+avx,+avx2,+fma,+f16c,+bmi,+bmi2,+lzcnt,+movbe,+popcnt,+sse4.1,+sse4.2,+ssse3"
PRESETS = {
    "avx2": ("x86-64-v3", _AVX2, 8),
    "avx2-w4": ("x86-64-v3", _AVX2, 4),
}
"""Named targets: (LLVM CPU name, LLVM feature string, vector width)."""

#: LLVM feature names whose ``/proc/cpuinfo`` flag is spelled differently.
_CPUINFO_FLAG = {"sse4.1": "sse4_1", "sse4.2": "sse4_2", "bmi": "bmi1", "lzcnt": "abm"}

_WIDTHS = (1, 4, 8, 16)

# Mangled C++ names of Dr.Jit's C API (drjit-core/include/drjit-core/jit.h).
_SET_TARGET = "_Z19jit_llvm_set_targetPKcS0_j"
_TARGET_CPU = "_Z19jit_llvm_target_cpuv"
_VECTOR_WIDTH = "_Z21jit_llvm_vector_widthv"

_state: dict = {"applied": None}


def parse_jit_target(text: str) -> tuple[str, str, int] | None:
    """Read a ``STEREOVAR_JIT_TARGET`` value.

    Parameters
    ----------
    text : str
        ``host`` or empty, a :data:`PRESETS` name, or ``CPU:FEATURES:WIDTH``.

    Returns
    -------
    tuple of (str, str, int) or None
        LLVM CPU name, feature string and vector width; None for the host's own target.

    Raises
    ------
    BackendError
        The value is none of these (one line listing the forms).

    Examples
    --------
    >>> parse_jit_target("host") is None
    True
    >>> parse_jit_target("avx2")[::2]
    ('x86-64-v3', 8)
    >>> parse_jit_target("haswell:+avx2,+fma:4")
    ('haswell', '+avx2,+fma', 4)
    """
    value = text.strip()
    if value in ("", "host"):
        return None
    if value in PRESETS:
        return PRESETS[value]
    parts = value.split(":")
    usage = (
        f"{ENV}={text!r} is not a JIT target; use host, "
        + ", ".join(PRESETS)
        + ", or CPU:FEATURES:WIDTH (e.g. haswell:+avx,+avx2,+fma:8) with WIDTH one of "
        + "/".join(map(str, _WIDTHS))
    )
    if len(parts) != 3 or not parts[0] or not parts[2].isdigit() or int(parts[2]) not in _WIDTHS:
        raise BackendError(usage)
    return parts[0], parts[1], int(parts[2])


def missing_cpu_flags(features: str, cpuinfo: str | None = None) -> list[str]:
    """The ``+feature`` entries of an LLVM feature string that this CPU lacks.

    Parameters
    ----------
    features : str
        Comma-separated LLVM features (``+avx2,+fma``).
    cpuinfo : str, optional
        The text of ``/proc/cpuinfo``; read when None. Without it (not Linux) nothing is
        reported missing.

    Examples
    --------
    >>> missing_cpu_flags("+avx2,+fma,+avx512f", "flags : fpu sse4_2 avx avx2 fma")
    ['avx512f']
    """
    if cpuinfo is None:
        try:
            cpuinfo = Path("/proc/cpuinfo").read_text()
        except OSError:
            return []
    flags = set()
    for line in cpuinfo.splitlines():
        if line.split(":", 1)[0].strip() == "flags":
            flags.update(line.split(":", 1)[1].split())
    wanted = [f[1:] for f in features.split(",") if f.startswith("+")]
    return [f for f in wanted if _CPUINFO_FLAG.get(f, f).replace(".", "_") not in flags]


def _core():
    """Dr.Jit's ``libdrjit-core`` (already loaded by ``import drjit``)."""
    drjit = sys.modules["drjit"]
    return ctypes.CDLL(str(Path(drjit.__file__).parent / "libdrjit-core.so"))


def current_jit_target() -> str:
    """The LLVM back end's target as ``CPU/WIDTH`` (e.g. ``znver3/8``), for provenance;
    empty when Dr.Jit is not imported or its LLVM back end is inactive."""
    drjit = sys.modules.get("drjit")
    if drjit is None or not drjit.has_backend(drjit.JitBackend.LLVM):
        return ""
    lib = _core()
    cpu, width = getattr(lib, _TARGET_CPU), getattr(lib, _VECTOR_WIDTH)
    cpu.restype, width.restype = ctypes.c_char_p, ctypes.c_uint32
    return f"{(cpu() or b'').decode()}/{width()}"


def apply_jit_target() -> tuple[str, str, int] | None:
    """Compile Dr.Jit's LLVM kernels for ``STEREOVAR_JIT_TARGET`` (once per process).

    Call after ``import drjit``; does nothing for ``host`` or when the LLVM back end is
    inactive.

    Returns
    -------
    tuple or None
        The target applied, or None.

    Raises
    ------
    BackendError
        The value cannot be read, or the target needs instructions this CPU lacks.
    """
    target = parse_jit_target(os.environ.get(ENV, ""))
    if target is None or _state["applied"] == target:
        return _state["applied"]
    missing = missing_cpu_flags(target[1])
    if missing:
        raise BackendError(
            f"{ENV}={os.environ[ENV]!r} needs {', '.join(missing)}, which this CPU lacks "
            "(its kernels would crash); choose a target this CPU runs, e.g. avx2-w4, or host"
        )
    drjit = sys.modules["drjit"]
    if not drjit.has_backend(drjit.JitBackend.LLVM):
        return None
    setter = getattr(_core(), _SET_TARGET)
    setter.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
    setter.restype = None
    setter(target[0].encode(), target[1].encode(), target[2])
    _state["applied"] = target
    return target
