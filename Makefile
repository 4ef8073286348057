# Quick start: `make demo` and `make test` on a fresh clone are the whole set-up.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
export PYVISTA_OFF_SCREEN := true
export MPLBACKEND := Agg
export OPENBLAS_NUM_THREADS ?= 1
export OMP_WAIT_POLICY ?= passive
# pytest-xdist workers of `make test` (0: one process). Two by default: the default selection
# (1,115 tests, warm numba cache, reports/quick/ present as in CI) measured in interleaved pairs
# on the shared 2-core machine, serial vs two workers, wall (CPU): load 4: 183 s (114 s) vs
# 181 s (156 s); load 2: 125 s (125 s) vs 75 s (138 s); idle: 108 s (104 s) vs 71 s (111 s).
# Two workers win every pair, by 1 % at load 4, where they cost a third more CPU: on a busy
# machine `make test TEST_WORKERS=0` is the kinder choice.
# Test files are kept whole on one worker (--dist loadfile): a module's shared fixtures are
# built once; numba's on-disk kernel cache is safe to fill from two processes (it writes
# through a temporary file and an atomic rename).
TEST_WORKERS ?= 2
# The packages mypy checks in `make test` (clean: any error fails the target).
TYPED = springfem reference_fem corotational peers
XDIST = $(if $(filter-out 0,$(TEST_WORKERS)),-n $(TEST_WORKERS) --dist loadfile)

.PHONY: demo test test-slow lint docs report quick-report bench clean

$(BIN)/python:
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -e .
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -e '.[test]'
	touch $@ $(VENV)/.installed

$(VENV)/.installed-docs: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -e '.[docs]'
	touch $@ $(VENV)/.installed

demo: $(VENV)/.installed
	$(BIN)/springfem compare

# Default selection (not slow); it checks reports/quick/ when `make quick-report` wrote it.
test: $(VENV)/.installed-test
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy $(TYPED)
	$(BIN)/python -m pytest -q $(XDIST)

# The slow tests alone (full-size studies, a fresh quick report).
test-slow: $(VENV)/.installed-test
	$(BIN)/python -m pytest -q -m slow

lint: $(VENV)/.installed-test
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy $(TYPED)

# The manual and API pages into docs/_build/html; any Sphinx warning fails the build. The
# build runs the tutorial's commands (docs/tutorial.rst, in docs/_build/tutorial) and
# generates the CLI and scene-file references from the parsers; CI runs it after the tests.
docs: $(VENV)/.installed-docs
	$(BIN)/python -m sphinx -W --keep-going -b html docs docs/_build/html

report: $(VENV)/.installed
	$(BIN)/springfem report

quick-report: $(VENV)/.installed
	$(BIN)/springfem report --quick --out reports/quick

bench: $(VENV)/.installed
	$(BIN)/springfem bench forces
	$(BIN)/springfem bench fem

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .ruff_cache
