# Every target does its own setup: a fresh machine needs only Python 3.11, pip and make.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
DOCS_STAMP := $(VENV)/.installed-docs

.PHONY: run test bench lint typecheck docs clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# After installing, compile the numba kernels once into numba's cache (tools/warm_numba.py).
$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[test]'
	$(BIN)/python tools/warm_numba.py
	touch $(STAMP)

run: $(STAMP)
	$(BIN)/eclipsebench run

# The suite runs on every core (pytest-xdist): a worker runs a whole test file, and one worker
# the files that start Dask clusters (tests/conftest.py). TEST_WORKERS=0: in one process.
# Python's bytecode caches (the gitignored __pycache__ folders) are written even where
# PYTHONDONTWRITEBYTECODE is set: otherwise every worker and every process a test starts
# compiles the package and rewrites the tests' asserts again (~2.6 s of CPU per collection).
TEST_WORKERS ?= auto
test: $(STAMP)
	PYTHONDONTWRITEBYTECODE= $(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadfile

$(DOCS_STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[test,docs]'
	touch $(DOCS_STAMP)

# The documentation site (Sphinx, numpydoc, myst-parser): any warning fails the build.
docs: $(DOCS_STAMP)
	$(BIN)/python -m sphinx -W --keep-going -b html docs docs/_build/html

bench: $(STAMP)
	$(BIN)/python bench/run_all.py

lint: $(STAMP)
	$(BIN)/ruff check src tests bench

# mypy's settings (Python 3.11, the libraries without type information) are in pyproject.toml.
typecheck: $(STAMP)
	$(BIN)/mypy src

clean:
	rm -rf $(VENV) build *.egg-info src/*.egg-info docs/_build docs/generated
