"""Choose the Mitsuba 3 variant (CUDA, LLVM or scalar) in one place.

Dr.Jit's LLVM backend loads ``libLLVM`` at import time. Its own search may pick a
library that is too old: on Debian 12 it finds libLLVM 15, which aborts the process inside
Mitsuba 3.9 ("Cannot select ... fminimum"). This module therefore finds a libLLVM with
major version >= 16 *before* Dr.Jit is imported and points ``DRJIT_LIBLLVM_PATH`` at it.

Importing this module is cheap and does not import numpy, Dr.Jit or Mitsuba, so that
``scripts/setup.sh`` can run :func:`find_libllvm` with the system Python before any
dependency is installed. Nothing else in the package may import ``mitsuba`` or ``drjit``
directly: call :func:`load_mitsuba` instead.

Environment variables
---------------------
DRJIT_LIBLLVM_PATH
    Read by Dr.Jit. When a user sets it, it is respected (a file name showing a version
    below 16 is rejected); otherwise :func:`configure_llvm` sets it.
STEREOVAR_LLVM_SEARCH_DIRS
    ``os.pathsep``-separated directories that replace the default libLLVM search path
    (an empty value searches nothing, which simulates a machine without libLLVM).
STEREOVAR_JIT_TARGET
    The CPU Dr.Jit's LLVM kernels are compiled for (:mod:`.jit_target`; default ``host``).
"""

from __future__ import annotations

import glob
import os
import re
import sys
import warnings
from pathlib import Path

from stereovar.errors import BackendError
from stereovar.renderers.mitsuba.jit_target import apply_jit_target, current_jit_target
from stereovar.renderers.quiet import silenced

__all__ = [
    "MIN_LLVM_MAJOR",
    "BackendWarning",
    "available_variants",
    "configure_llvm",
    "describe_backend",
    "find_libllvm",
    "load_mitsuba",
    "select_variant",
]

#: Oldest libLLVM major version that works with the supported Mitsuba/Dr.Jit releases.
MIN_LLVM_MAJOR = 16

#: The variants :func:`select_variant` chooses among, in order of preference.
PREFERRED_VARIANTS = ("cuda_ad_rgb", "llvm_ad_rgb", "scalar_rgb")

#: Value given to ``DRJIT_LIBLLVM_PATH`` when no usable libLLVM exists. Dr.Jit fails to load
#: it, reports the LLVM backend as inactive and does *not* fall back to its own search
#: (which could load an old libLLVM that aborts the process).
NO_LIBLLVM_SENTINEL = "/nonexistent/stereovar-found-no-libLLVM-16-or-newer/libLLVM.so"

LLVM_FIX_HINT = (
    "fix: `sudo apt-get install libllvm19` (Debian/Ubuntu) "
    "or set DRJIT_LIBLLVM_PATH to a libLLVM >= 16"
)

_SEARCH_ENV = "STEREOVAR_LLVM_SEARCH_DIRS"
_DRJIT_ENV = "DRJIT_LIBLLVM_PATH"

_FIXED_DIRS = (
    "/usr/lib/x86_64-linux-gnu",
    "/usr/lib/aarch64-linux-gnu",
    "/usr/lib64",
    "/usr/lib",
    "/usr/local/lib",
)
_GLOB_DIRS = ("/usr/lib/llvm-*/lib",)
_MACOS_DIRS = ("/opt/homebrew/opt/llvm/lib", "/usr/local/opt/llvm/lib")

# libLLVM-19.so, libLLVM-19.1.so, libLLVM-17.so.1, libLLVM-14.0.6.so.1, libLLVM-19.dylib
_NAME_DASH = re.compile(r"^libLLVM-(\d+(?:\.\d+)*)\.(?:so(?:\.\d+)*|dylib)$")
# libLLVM.so.19, libLLVM.so.19.1
_NAME_SOVERSION = re.compile(r"^libLLVM\.so\.(\d+(?:\.\d+)*)$")
# libLLVM.so / libLLVM.dylib: version taken from an enclosing directory
_NAME_PLAIN = re.compile(r"^libLLVM\.(?:so|dylib)$")
# llvm-19, llvm@18, llvm-19.1, or a Homebrew Cellar version directory such as 19.1.7
_DIR_VERSION = re.compile(r"^(?:llvm[-@])?(\d+(?:\.\d+)*)$")

_state: dict = {"selected": {}, "warned": False, "user_libllvm": False, "configured": False}


class BackendWarning(UserWarning):
    """Emitted when Mitsuba falls back to the slow scalar variant."""


def _version_tuple(text: str) -> tuple[int, ...]:
    return tuple(int(part) for part in text.split("."))


def _dir_version(path: Path) -> tuple[int, ...] | None:
    """Version from an enclosing dir: ``llvm-19/lib``, ``llvm@18/lib``, ``llvm/19.1.7/lib``."""
    candidates = [path, path.resolve()] if path.exists() else [path]
    for candidate in candidates:
        parents = list(candidate.parents)
        for index, parent in enumerate(parents[:3]):
            match = _DIR_VERSION.match(parent.name)
            if not match:
                continue
            named = parent.name.startswith("llvm")
            in_llvm_dir = index + 1 < len(parents) and parents[index + 1].name.startswith("llvm")
            if named or in_llvm_dir:
                return _version_tuple(match.group(1))
    return None


def libllvm_version(path) -> tuple[int, ...] | None:
    """Version of a libLLVM shared library, read from its file or directory name.

    Parameters
    ----------
    path : str or os.PathLike
        A path such as ``/usr/lib/x86_64-linux-gnu/libLLVM-19.so``,
        ``/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1`` or ``/usr/lib/llvm-19/lib/libLLVM.so``.

    Returns
    -------
    tuple of int or None
        The version, e.g. ``(19,)`` or ``(19, 1)``; None when the name shows no version.
    """
    path = Path(path)
    for pattern in (_NAME_DASH, _NAME_SOVERSION):
        match = pattern.match(path.name)
        if match:
            return _version_tuple(match.group(1))
    if _NAME_PLAIN.match(path.name):
        return _dir_version(path)
    return None


def default_search_dirs() -> list[Path]:
    """Directories searched by :func:`find_libllvm` when none are given.

    Returns
    -------
    list of pathlib.Path
        ``$STEREOVAR_LLVM_SEARCH_DIRS`` (``os.pathsep``-separated) when that variable is set;
        otherwise ``$LD_LIBRARY_PATH`` entries, ``$CONDA_PREFIX/lib``, the usual system
        library directories, ``/usr/lib/llvm-*/lib`` and the Homebrew LLVM directories.
    """
    override = os.environ.get(_SEARCH_ENV)
    if override is not None:
        return [Path(entry) for entry in override.split(os.pathsep) if entry]
    dirs = [entry for entry in os.environ.get("LD_LIBRARY_PATH", "").split(os.pathsep) if entry]
    if os.environ.get("CONDA_PREFIX"):
        dirs.append(os.path.join(os.environ["CONDA_PREFIX"], "lib"))
    dirs.extend(_FIXED_DIRS)
    for pattern in _GLOB_DIRS:
        dirs.extend(sorted(glob.glob(pattern)))
    dirs.extend(_MACOS_DIRS)
    return [Path(entry) for entry in dirs]


def find_libllvm(search_dirs=None) -> Path | None:
    """Find the newest libLLVM shared library with major version >= 16.

    Recognised file names include ``libLLVM-19.so``, ``libLLVM-19.1.so``,
    ``libLLVM.so.19.1``, ``libLLVM.so.19``, ``libLLVM-17.so.1``, ``libLLVM-19.dylib`` and
    ``libLLVM.so``/``libLLVM.dylib`` inside a versioned directory (``llvm-19/lib``,
    Homebrew's ``Cellar/llvm/19.1.7/lib``). Files whose version is unknown or below 16 are
    ignored, as are broken symbolic links.

    Parameters
    ----------
    search_dirs : iterable of str or os.PathLike, optional
        Directories to search, in order of preference. Defaults to
        :func:`default_search_dirs`.

    Returns
    -------
    pathlib.Path or None
        The library with the highest version (the first directory wins a tie), or None
        when there is none.
    """
    dirs = default_search_dirs() if search_dirs is None else [Path(d) for d in search_dirs]
    best: tuple[tuple[int, ...], int, Path] | None = None
    order = 0
    for directory in dirs:
        try:
            entries = sorted(directory.iterdir())
        except OSError:
            continue
        for entry in entries:
            if not entry.name.startswith("libLLVM"):
                continue
            version = libllvm_version(entry)
            if version is None or version[0] < MIN_LLVM_MAJOR or not entry.is_file():
                continue
            order += 1
            # Highest version first; among equal versions the earliest found.
            if best is None or (version, -order) > (best[0], -best[1]):
                best = (version, order, entry)
    return None if best is None else best[2]


def configure_llvm() -> Path | None:
    """Point Dr.Jit at a working libLLVM; call before ``drjit``/``mitsuba`` are imported.

    A ``DRJIT_LIBLLVM_PATH`` set by the user is respected. Otherwise it is set to
    :func:`find_libllvm`'s result or, when no libLLVM >= 16 exists, to a path that cannot
    load, so that Dr.Jit reports its LLVM backend as inactive instead of loading an older
    libLLVM that aborts the process. Once Dr.Jit is imported, changing the variable has no
    effect; the function then only reports the current value.

    Returns
    -------
    pathlib.Path or None
        The libLLVM Dr.Jit will load, or None when there is none.

    Raises
    ------
    BackendError
        If the user's ``DRJIT_LIBLLVM_PATH`` names a libLLVM older than 16.
    """
    current = os.environ.get(_DRJIT_ENV, "")
    if current and current != NO_LIBLLVM_SENTINEL:
        if "drjit" not in sys.modules and not _state["configured"]:
            _state["user_libllvm"] = True  # set before this process looked for one
        version = libllvm_version(current)
        if version is not None and version[0] < MIN_LLVM_MAJOR:
            raise BackendError(
                f"DRJIT_LIBLLVM_PATH={current} is libLLVM {version[0]}, which crashes "
                f"Mitsuba; {LLVM_FIX_HINT} (or unset it to search automatically)"
            )
        return Path(current)
    if "drjit" in sys.modules:
        return None
    found = find_libllvm()
    os.environ[_DRJIT_ENV] = str(found) if found is not None else NO_LIBLLVM_SENTINEL
    _state["configured"] = True
    return found


def _import_drjit():
    """Configure libLLVM, then import Dr.Jit (without its noise about the sentinel path) and
    set the LLVM back end's target (:func:`.jit_target.apply_jit_target`)."""
    configure_llvm()
    quiet = "drjit" not in sys.modules and os.environ.get(_DRJIT_ENV) == NO_LIBLLVM_SENTINEL
    with silenced(2, quiet):
        import drjit
    apply_jit_target()
    return drjit


def _import_mitsuba():
    _import_drjit()
    import mitsuba

    return mitsuba


def _backend_ready(variant: str) -> bool:
    """Whether the Dr.Jit backend a variant needs is active in this process."""
    dr = _import_drjit()
    if variant.startswith("cuda_"):
        return bool(dr.has_backend(dr.JitBackend.CUDA))
    if variant.startswith("llvm_"):
        return bool(dr.has_backend(dr.JitBackend.LLVM))
    return True


def _usable_variants(candidates) -> list[str]:
    compiled = set(_import_mitsuba().variants())
    return [v for v in candidates if v in compiled and _backend_ready(v)]


def available_variants() -> list[str]:
    """Variants among ``cuda_ad_rgb``, ``llvm_ad_rgb`` and ``scalar_rgb`` usable here.

    Returns
    -------
    list of str
        In order of preference; a variant is listed when Mitsuba was built with it and
        ``drjit.has_backend`` reports its backend (CUDA or LLVM) active.
    """
    return _usable_variants(PREFERRED_VARIANTS)


def _flavour(variant: str) -> str:
    """A variant's colour representation without its backend: ``cuda_ad_rgb`` -> ``rgb``."""
    return re.sub(r"^(?:cuda_ad|llvm_ad|cuda|llvm|scalar)_", "", variant)


def _why_unavailable(variant: str) -> str:
    if variant.startswith("cuda_"):
        return "Dr.Jit found no usable CUDA device (NVIDIA GPU and driver)"
    current = os.environ.get(_DRJIT_ENV, "")
    if current and current != NO_LIBLLVM_SENTINEL:
        return f"Dr.Jit could not load DRJIT_LIBLLVM_PATH={current}; {LLVM_FIX_HINT}"
    return f"no libLLVM >= {MIN_LLVM_MAJOR} was found; {LLVM_FIX_HINT}"


def _warn_scalar_fallback() -> None:
    if _state["warned"]:
        return
    _state["warned"] = True
    message = f"using the slow scalar_rgb Mitsuba variant because {_why_unavailable('llvm_ad_rgb')}"
    # An explicit location with no source line keeps the printed warning on one line.
    warnings.warn_explicit(message, BackendWarning, filename=__name__, lineno=0)


def select_variant(requested: str = "auto") -> str:
    """Choose the Mitsuba variant to render with.

    Parameters
    ----------
    requested : str, default "auto"
        ``"auto"`` picks ``cuda_ad_rgb`` when a CUDA GPU is usable, else ``llvm_ad_rgb`` when
        a working libLLVM is loaded, else ``scalar_rgb`` with a :class:`BackendWarning`
        saying how to get LLVM. Any other value must be one of ``mitsuba.variants()`` and
        is returned only when its backend is available.

    Returns
    -------
    str
        The variant name.

    Raises
    ------
    BackendError
        If a forced variant is unknown or its backend is unavailable; the one-line message
        names the variant, the reason and the available variants.
    """
    if requested == "auto":
        available = available_variants()
        if not available:
            raise BackendError("no Mitsuba variant is usable: mitsuba provides no *_rgb variant")
        if available[0] == "scalar_rgb":
            if _state["user_libllvm"]:
                # the user pointed Dr.Jit at a libLLVM that does not load: rendering with
                # scalar_rgb instead would mix back ends with runs where it did load
                raise BackendError(
                    f"{_why_unavailable('llvm_ad_rgb')} (or unset it to search automatically)"
                )
            _warn_scalar_fallback()
        return available[0]
    mi = _import_mitsuba()
    compiled = list(mi.variants())
    if requested not in compiled:
        raise BackendError(
            f"unknown Mitsuba variant '{requested}'; mitsuba {mi.__version__} provides: "
            f"{', '.join(compiled)} (or use 'auto')"
        )
    if not _backend_ready(requested):
        flavour = _flavour(requested)
        usable = _usable_variants([v for v in compiled if _flavour(v) == flavour])
        raise BackendError(
            f"Mitsuba variant '{requested}' is not available: {_why_unavailable(requested)}; "
            f"available here: {', '.join(usable) or 'none'} (or use 'auto')"
        )
    return requested


def load_mitsuba(requested: str = "auto"):
    """Import Mitsuba with the selected variant set.

    The selection for each ``requested`` value is made once per process; a later call
    asking for a different variant switches Mitsuba to it.

    Parameters
    ----------
    requested : str, default "auto"
        Passed to :func:`select_variant`.

    Returns
    -------
    module
        The ``mitsuba`` module, with ``mitsuba.variant()`` set.

    Raises
    ------
    BackendError
        See :func:`select_variant`.
    """
    selected = _state["selected"]
    if requested not in selected:
        selected[requested] = select_variant(requested)
    mi = _import_mitsuba()
    if mi.variant() != selected[requested]:
        mi.set_variant(selected[requested])
    return mi


def describe_backend() -> dict:
    """Provenance of the rendering backend, for the attrs of stored artefacts.

    Returns
    -------
    dict
        ``variant`` (the current Mitsuba variant, or None before :func:`load_mitsuba`),
        ``libllvm`` (the path given to Dr.Jit, or None), ``jit_target`` (the CPU and
        vector width LLVM kernels are compiled for, e.g. ``znver3/8``; empty for CUDA and
        scalar variants), ``mitsuba_version`` and ``drjit_version``; all values are strings
        or None.
    """
    mi = _import_mitsuba()
    dr = sys.modules["drjit"]
    libllvm = os.environ.get(_DRJIT_ENV) or None
    llvm_active = bool(dr.has_backend(dr.JitBackend.LLVM))
    return {
        "variant": mi.variant(),
        "libllvm": libllvm if libllvm != NO_LIBLLVM_SENTINEL and llvm_active else None,
        "jit_target": current_jit_target() if mi.variant().startswith("llvm_") else "",
        "mitsuba_version": str(mi.__version__),
        "drjit_version": str(dr.__version__),
    }
