#!/usr/bin/env bash
# Snakemake runs this once in a new job environment made from stereovar.yaml (--sdm conda),
# with that environment active: it installs this stereovar itself, without dependencies
# (stereovar.yaml has them). The Snakefile puts the requirement that reinstalls the running
# stereovar (its checkout, its wheel file or its version) in STEREOVAR_REQUIREMENT
# (stereovar.workflow_home.install_requirement).
set -euo pipefail
if [ -z "${STEREOVAR_REQUIREMENT:-}" ]; then
    echo "stereovar post-deploy: error: STEREOVAR_REQUIREMENT is not set; run the workflow with an installed stereovar (pip install -e . in the checkout, or the wheel), or set it to a pip requirement for stereovar" >&2
    exit 1
fi
python -m pip install --no-deps --disable-pip-version-check --quiet "$STEREOVAR_REQUIREMENT"
# The requirement reaches Python as an argument, never as part of its source: a path or
# version with quotes or braces in it is printed as it is, not run.
python -c 'import stereovar, sys; sys.stdout.write(f"stereovar {stereovar.__version__} installed from {sys.argv[1]}\n")' "$STEREOVAR_REQUIREMENT"
