# stereovar: set up, run the default experiment, test, lint.
# `make run` and `make test` set up ./.venv first (scripts/setup.sh; fast when up to date).

VENV := .venv
PYTHON := $(VENV)/bin/python
SNAKEMAKE := $(VENV)/bin/snakemake

.PHONY: setup run test lint clean

setup:
	bash scripts/setup.sh

run: setup
	$(SNAKEMAKE) -j2 all

test: setup
	$(PYTHON) -m pytest

lint: setup
	$(PYTHON) -m ruff check .
	$(SNAKEMAKE) --lint

# Removes workflow outputs and Snakemake's state; never scenes/ or .venv.
clean:
	rm -rf results .snakemake
