# stereovar: set up, run the default experiment, test, lint.
# `make run` and `make test` set up ./.venv first (scripts/setup.sh; fast when up to date);
# `make docs` sets up only what the documentation needs (scripts/setup.sh --docs).

VENV := .venv
PYTHON := $(VENV)/bin/python
SNAKEMAKE := $(VENV)/bin/snakemake

.PHONY: setup run test test-other-cpu lint docs-setup docs docs-figures clean

setup:
	bash scripts/setup.sh

run: setup
	$(SNAKEMAKE) -j2 all

# Three pytest-xdist workers on the reference 2-core machine (the SLURM tests mostly wait on
# their scheduler, and a third worker fills that time); tests sharing a
# session run or a module's run stay on one worker, the longest groups first, in the order
# tests/conftest.py gives (not xdist's order by test count). The 25 slowest tests
# are listed at the end, so a slow test shows the day it lands. PYTEST_WORKERS=0 runs the
# suite in this process.
PYTEST_WORKERS ?= 3
PYTEST_ARGS := -n $(PYTEST_WORKERS) --dist loadgroup --no-loadscope-reorder --durations=25

test: setup
	$(PYTHON) -m pytest $(PYTEST_ARGS)

# The suite as another x86-64 CPU would run it: Dr.Jit's kernels compiled for a generic AVX2
# CPU with 4 lanes, numpy without its AVX2, FMA and AVX-512 kernels (docs/development.md: Results across
# machines).
test-other-cpu: setup
	STEREOVAR_JIT_TARGET=avx2-w4 NPY_DISABLE_CPU_FEATURES="AVX2 FMA3 AVX512F AVX512CD AVX512_SKX" \
		$(PYTHON) -m pytest $(PYTEST_ARGS)

lint: setup
	$(PYTHON) -m ruff check .
	$(SNAKEMAKE) --lint

# The documentation's set-up alone: the docs extra in .venv (scripts/setup.sh --docs: no
# Blender, no PyTorch, no libLLVM); a .venv that `make setup` made is used as it is.
docs-setup:
	bash scripts/setup.sh --docs

# The documentation site, warnings as errors; open docs/_build/html/index.html.
docs: docs-setup
	$(PYTHON) -m sphinx -W --keep-going -b html docs docs/_build/html

# The documentation's figures (docs/figures/*.png), from a tiny run and the example audit.
docs-figures: setup
	$(PYTHON) docs/figures/make_figures.py

# Removes workflow outputs and Snakemake's state; never scenes/ or .venv.
clean:
	rm -rf results .snakemake
