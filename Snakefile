# stereovar: cross-view Monte Carlo variance correlation in path-traced stereo.
# Wiring only: configuration and validation live in workflow/rules/common.smk, each feature's
# input functions and targets in workflow/rules/inputs/, every number is computed in
# src/stereovar.
from snakemake.utils import min_version

min_version("8.20")

# Config files read as stereovar reads YAML before Snakemake uses them: a tag such as
# !!python/object in config.yaml (which Snakemake reports naming neither the file nor the
# tag) or aliases that expand past what a config holds are one line naming file and line.
import os

from stereovar.config import check_config_files_or_exit
from stereovar.workflow_home import default_configfile, export_install_requirement

# config.yaml of the working directory, else the workflow's own (an installed stereovar run
# from a directory without one: `stereovar run`).
CONFIGFILE = default_configfile(workflow.basedir)
check_config_files_or_exit([CONFIGFILE, *workflow.overwrite_configfiles])
# What envs/stereovar.post-deploy.sh installs into a job's conda environment (--sdm conda).
export_install_requirement(os.environ)
# One BLAS thread per job: Snakemake runs jobs side by side, and OpenBLAS rounds a product
# differently with the threads it finds (a SLURM node's tables would differ from a laptop's
# in the last bit) and spins on cores other jobs use. Set it before a run to override.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# The jobs read every store numpy-backed: without dask, which xarray would otherwise import
# in each of them (stereovar). Set STEREOVAR_DASK=1 before a run to keep it.
os.environ.setdefault("STEREOVAR_DASK", "0")


configfile: CONFIGFILE


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"


rule all:
    input:
        all_targets(),
    default_target: True
    localrule: True


include: "workflow/rules/scenes.smk"
include: "workflow/rules/ground_truth.smk"
include: "workflow/rules/preview.smk"
include: "workflow/rules/render.smk"
include: "workflow/rules/variance.smk"
include: "workflow/rules/correlation.smk"
include: "workflow/rules/tables.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/intervention.smk"
include: "workflow/rules/claims.smk"
include: "workflow/rules/estimators.smk"
include: "workflow/rules/audit.smk"
include: "workflow/rules/mitigations.smk"
include: "workflow/rules/calibration.smk"
include: "workflow/rules/probe.smk"
include: "workflow/rules/probe_model.smk"
include: "workflow/rules/generators.smk"


onstart:
    preflight()


onsuccess:
    print_summary()
