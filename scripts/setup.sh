#!/usr/bin/env bash
# Set up stereovar in ./.venv: a libLLVM >= 16 for Dr.Jit, Python >= 3.10,
# `pip install -e ".[test,cycles,mitigations,probe,docs]"` (skipped while pyproject.toml is unchanged;
# the cycles extra, Blender's bpy, installs on CPython 3.11 only; mitigations is pyoidn;
# probe is PyTorch 2.13.0, taken from PyTorch's CPU wheel index on Linux where that index
# answers (PyPI's Linux torch is the CUDA build: see pyproject.toml's probe extra);
# docs is Sphinx and its extensions, for `make docs` and the documentation test),
# and, where apt-get can install it, Debian's chromium for the results page's browser test.
# Called by `make setup`, `make run` and `make test`; safe to run again.
#
# scripts/setup.sh --docs (called by `make docs`) sets up only what the documentation build
# needs: Python >= 3.10 and `pip install -e ".[docs]"` in ./.venv (stereovar's own
# dependencies and Sphinx; no Blender, no PyTorch, no pyoidn, no libLLVM, no chromium). A
# .venv that the full set-up made is used as it is.
#
# Environment:
#   PYTHON                      interpreter used to create .venv (default: python3)
#   DRJIT_LIBLLVM_PATH          use this libLLVM instead of searching
#   STEREOVAR_LLVM_SEARCH_DIRS  directories to search for libLLVM (os.pathsep-separated)
#   STEREOVAR_ALLOW_SCALAR=1    continue without libLLVM (slow scalar Mitsuba variant)
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
PYTHON="${PYTHON:-python3}"
VENV=.venv
STAMP="$VENV/.stereovar-setup"
DOCS_STAMP="$VENV/.stereovar-setup-docs"

say() { echo "stereovar setup: $*"; }
die() { echo "stereovar setup: error: $*" >&2; exit 1; }

MODE=full
case "${1-}" in
    "") ;;
    --docs) MODE=docs ;;
    *) die "unknown option '$1'; use scripts/setup.sh (everything) or scripts/setup.sh --docs (the documentation build only)" ;;
esac

make_venv() {  # creates $VENV unless a working one is there; sets want (the stamps' content)
    if [ ! -x "$VENV/bin/python" ] || ! "$VENV/bin/python" -c '' 2>/dev/null; then
        "$PYTHON" -c 'import venv, ensurepip' 2>/dev/null \
            || die "'$PYTHON' lacks the venv module (with ensurepip); install it with: sudo apt-get install python3-venv"
        say "creating $VENV with $("$PYTHON" -c 'import sys; print(sys.executable)')"
        "$PYTHON" -m venv --clear "$VENV" || die "'$PYTHON -m venv $VENV' failed; on Debian/Ubuntu: sudo apt-get install python3-venv"
    fi
    want="$("$VENV/bin/python" -c 'import hashlib, os; print(hashlib.sha256(open("pyproject.toml", "rb").read()).hexdigest(), os.getcwd())')"
}

# --- Python ------------------------------------------------------------------
command -v "$PYTHON" >/dev/null 2>&1 \
    || die "'$PYTHON' not found; install Python >= 3.10 (Debian/Ubuntu: sudo apt-get install python3 python3-venv) or set PYTHON=/path/to/python3"
"$PYTHON" -c 'import sys; sys.exit(sys.version_info < (3, 10))' \
    || die "Python >= 3.10 is needed, '$PYTHON' is $("$PYTHON" -c 'import platform; print(platform.python_version())'); install a newer one or set PYTHON=/path/to/python3.10+"

# --- the documentation build's set-up alone (--docs) -------------------------
if [ "$MODE" = docs ]; then
    make_venv
    if [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$want" ]; then
        say "dependencies up to date (the full set-up, the docs extra included)"
    elif [ -f "$DOCS_STAMP" ] && [ "$(cat "$DOCS_STAMP")" = "$want" ]; then
        say "the documentation's dependencies up to date (pyproject.toml unchanged)"
    else
        say "installing stereovar and the docs extra into $VENV (pip install -e \".[docs]\": no Blender, no PyTorch)"
        "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check -e ".[docs]" \
            || die "pip install -e \".[docs]\" failed (see the pip output above)"
        echo "$want" >"$DOCS_STAMP"
    fi
    say "ready to build the documentation"
    exit 0
fi

# --- libLLVM for Dr.Jit's LLVM backend ---------------------------------------
# Reuses stereovar.renderers.mitsuba.backend (importable without any dependency installed).
find_llvm() {
    "$PYTHON" - <<'EOF'
import os, sys
sys.path.insert(0, "src")
from stereovar.renderers.mitsuba.backend import configure_llvm
from stereovar.errors import BackendError
try:
    path = configure_llvm()
except BackendError as err:
    print(f"stereovar setup: error: {err}", file=sys.stderr)
    sys.exit(2)
if path is not None and not path.is_file():
    print(f"stereovar setup: error: DRJIT_LIBLLVM_PATH={path} does not exist; point it at a "
          "libLLVM >= 16 or unset it", file=sys.stderr)
    sys.exit(2)
print(path or "")
EOF
}

LLVM_FIX="fix: sudo apt-get install libllvm19 (Debian/Ubuntu; macOS: brew install llvm), or set DRJIT_LIBLLVM_PATH=/path/to/libLLVM-19.so; or set STEREOVAR_ALLOW_SCALAR=1 to continue with the slow scalar Mitsuba backend"

apt_candidate() {  # prints the candidate version of a package, or nothing
    apt-cache policy "$1" 2>/dev/null | awk '/Candidate:/ { if ($2 != "(none)") print $2 }'
}

apt_install_llvm() {  # $@: command prefix (nothing, or sudo -n)
    local v
    for v in 19 18 17 16; do
        if [ -n "$(apt_candidate "libllvm$v")" ]; then
            say "installing libllvm$v with apt-get"
            "$@" env DEBIAN_FRONTEND=noninteractive \
                apt-get install -y -q --no-install-recommends "libllvm$v" >/dev/null
            return
        fi
    done
    return 1
}

apt_root() {  # sets PREFIX for apt-get (nothing as root, else sudo -n); INSTALL_NOTE if neither
    PREFIX=()
    if ! command -v apt-get >/dev/null 2>&1; then
        INSTALL_NOTE="no apt-get here to install it automatically"
        return 1
    fi
    if [ "$(id -u)" -ne 0 ]; then
        if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
            PREFIX=(sudo -n)
        else
            INSTALL_NOTE="not installed automatically (not root, no password-less sudo)"
            return 1
        fi
    fi
}

install_llvm() {  # sets INSTALL_NOTE when it cannot or did not install
    apt_root || return 1
    local prefix=(${PREFIX[@]+"${PREFIX[@]}"})
    local updated=0
    if [ -z "$(apt_candidate libllvm19)" ]; then
        say "apt-get update (libllvm19 not in the package lists)"
        ${prefix[@]+"${prefix[@]}"} apt-get update -q >/dev/null && updated=1
    fi
    apt_install_llvm ${prefix[@]+"${prefix[@]}"} && return 0
    if [ "$updated" -eq 0 ]; then
        say "install failed; apt-get update and retry"
        ${prefix[@]+"${prefix[@]}"} apt-get update -q >/dev/null \
            && apt_install_llvm ${prefix[@]+"${prefix[@]}"} && return 0
    fi
    INSTALL_NOTE="apt-get could not install libllvm19/18/17/16"
    return 1
}

INSTALL_NOTE=""
llvm_status=0
LLVM_PATH="$(find_llvm)" || llvm_status=$?
[ "$llvm_status" -eq 2 ] && exit 1
[ "$llvm_status" -eq 0 ] || die "could not run the libLLVM search with '$PYTHON'"

if [ -z "$LLVM_PATH" ]; then
    if [ "${STEREOVAR_ALLOW_SCALAR:-0}" = 1 ]; then
        say "warning: no libLLVM >= 16; continuing with the slow scalar Mitsuba backend (STEREOVAR_ALLOW_SCALAR=1)"
    elif install_llvm; then
        LLVM_PATH="$(find_llvm)" || exit 1
        [ -n "$LLVM_PATH" ] || die "installed libLLVM with apt-get but found no libLLVM >= 16 in the search path (STEREOVAR_LLVM_SEARCH_DIRS=${STEREOVAR_LLVM_SEARCH_DIRS-unset}); $LLVM_FIX"
    else
        die "no libLLVM >= 16 found (Dr.Jit's LLVM backend needs it; libLLVM 15 crashes Mitsuba), $INSTALL_NOTE; $LLVM_FIX"
    fi
fi
[ -z "$LLVM_PATH" ] || say "libLLVM: $LLVM_PATH"

# --- virtual environment -----------------------------------------------------
make_venv
if [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$want" ]; then
    say "dependencies up to date (pyproject.toml unchanged)"
else
    # PyTorch's CPU wheels, as the README's install line names them: on Linux, PyPI's torch is
    # the CUDA build (several GB). The index is added only where it answers, since pip retries
    # an unreachable index for every package it resolves.
    TORCH_CPU_INDEX="https://download.pytorch.org/whl/cpu"
    INDEX_ARGS=()
    if [ "$(uname -s)" = Linux ] && "$VENV/bin/python" -c "import urllib.request, sys; urllib.request.urlopen(sys.argv[1] + '/torch/', timeout=5)" "$TORCH_CPU_INDEX" 2>/dev/null; then
        INDEX_ARGS=(--extra-index-url "$TORCH_CPU_INDEX")
    fi
    say "installing stereovar and its dependencies into $VENV (pip install -e \".[test,cycles,mitigations,probe,docs]\" ${INDEX_ARGS[*]+${INDEX_ARGS[*]}})"
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check ${INDEX_ARGS[@]+"${INDEX_ARGS[@]}"} -e ".[test,cycles,mitigations,probe,docs]" \
        || die "pip install -e \".[test,cycles,mitigations,probe,docs]\" failed (see the pip output above)"
    echo "$want" >"$STAMP"
fi

# --- Chromium for the results page's browser test (optional) ------------------
# tests/test_results_page.py opens results/index.html in headless Chromium (Debian's
# `chromium`); without it that one test is skipped. Set-up never fails here: a failed install
# is one line, and is not tried again while its note is in .venv.
CHROMIUM_STAMP="$VENV/.stereovar-chromium"

install_chromium() {  # sets INSTALL_NOTE when it cannot or did not install
    apt_root || return 1
    if [ -z "$(apt_candidate chromium)" ]; then
        say "apt-get update (chromium not in the package lists)"
        ${PREFIX[@]+"${PREFIX[@]}"} apt-get update -q >/dev/null 2>&1 || true
    fi
    if [ -z "$(apt_candidate chromium)" ]; then
        INSTALL_NOTE="no chromium package in the apt sources"
        return 1
    fi
    say "installing chromium with apt-get (for the results page's browser test)"
    ${PREFIX[@]+"${PREFIX[@]}"} env DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -q --no-install-recommends chromium >/dev/null 2>&1 && return 0
    INSTALL_NOTE="apt-get install chromium failed"
    return 1
}

if command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1; then
    :
elif [ -f "$CHROMIUM_STAMP" ]; then
    say "no chromium: $(cat "$CHROMIUM_STAMP") (delete $CHROMIUM_STAMP to try again); the results page's browser test will be skipped"
elif install_chromium; then
    say "chromium: $(command -v chromium)"
else
    echo "$INSTALL_NOTE" >"$CHROMIUM_STAMP"
    say "no chromium: $INSTALL_NOTE; the results page's browser test will be skipped"
fi

variant="$("$VENV/bin/python" -c 'import stereovar.renderers.mitsuba.backend as b; print(b.select_variant())')" \
    || die "Mitsuba could not start in $VENV (see the error above)"
if cycles="$("$VENV/bin/python" -c 'import bpy; print(bpy.app.version_string)' 2>/dev/null)"; then
    cycles="Blender $cycles (render.renderer: cycles)"
else
    cycles="unavailable: bpy wheels exist for CPython 3.11 only, this is $("$VENV/bin/python" -c 'import platform; print(platform.python_version())')"
fi
say "ready; Mitsuba variant: $variant; Cycles: $cycles"
