# The two commands of the README:
#   make run    set everything up (once) and run the default docking
#   make test   set everything up (once) and run the fast test suite
# Only Python >= 3.11 and make are needed; everything else installs into .venv.

PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: run test test-slow test-wheel test-all lint benchmark benchmark-check setup gl clean notebook

setup: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -c 'import sys; sys.exit("compliant-docking needs Python >= 3.11, found " + sys.version.split()[0]) if sys.version_info < (3, 11) else None'
	@echo "setting up $(VENV) (once): compliant-docking with MuJoCo, Pinocchio, ProxSuite, Hydra, numba"
	@echo "  and every optional feature (the test and dev extras); about 5 min on a fresh machine,"
	@echo "  about 1.5 min with a warm pip cache. pip's own output: $(VENV)/install.log"
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --upgrade pip > $(VENV)/install.log 2>&1 || { tail -20 $(VENV)/install.log; exit 1; }
	$(PY) -m pip install --progress-bar off -e '.[test,dev]' >> $(VENV)/install.log 2>&1 || { tail -20 $(VENV)/install.log; exit 1; }
	@echo "  installed: $$($(PY) -m pip list 2>/dev/null | tail -n +3 | wc -l) packages in $(VENV)"
	touch $(STAMP)

run: $(STAMP) gl
	$(PY) -m compliant_docking $(ARGS)

# The test targets write Python's bytecode cache (__pycache__, git-ignored, where numba keeps
# the kernels too) even where the environment turns it off (PYTHONDONTWRITEBYTECODE=1, set by
# many container images): without it each of the suite's processes (xdist workers, command
# lines, sweep workers) compiles the package from source again, and each worker rewrites the
# asserts of every test module again.
TEST_ENV := PYTHONDONTWRITEBYTECODE=

# the fast suite on every core (pytest-xdist); `make test XDIST=0` runs it in one process
XDIST ?= auto
test: $(STAMP) gl
	$(TEST_ENV) $(PY) -m pytest -q -n $(XDIST) $(PYTEST_ARGS)

# ruff (lint and format), mypy and import-linter's layer contract, configured in
# pyproject.toml; CI runs this before the tests
lint: $(STAMP)
	$(VENV)/bin/ruff check compliant_docking hydra_plugins tests benchmarks
	$(VENV)/bin/ruff format --check compliant_docking hydra_plugins tests benchmarks
	$(VENV)/bin/mypy
	$(VENV)/bin/lint-imports --no-cache --no-logo

test-slow: $(STAMP) gl
	$(TEST_ENV) $(PY) -m pytest -q -n $(XDIST) -m slow $(PYTEST_ARGS)

# the built wheel in a fresh virtualenv, run from outside the checkout (tests/test_package.py)
test-wheel: $(STAMP)
	$(PY) -m pytest -q -n 0 -m wheel $(PYTEST_ARGS)

# everything: the fast suite, the slow simulations and sweeps, the wheel
test-all: $(STAMP) gl
	$(TEST_ENV) $(PY) -m pytest -q -n $(XDIST) -m 'slow or wheel or not slow' $(PYTEST_ARGS)

# Offscreen rendering (render=video) without a display needs EGL (or OSMesa) from the
# system, not from pip: check that one loads; if not, install Debian's EGL packages
# (listed in compliant_docking/gl.py) when running as root, else print the command
# (docs/rendering.md).
gl: $(STAMP)
	@$(PY) compliant_docking/gl.py --quiet || { \
	  pkgs="$$($(PY) compliant_docking/gl.py --packages)"; \
	  if command -v apt-get >/dev/null 2>&1 && [ "$$(id -u)" = 0 ]; then \
	    echo "installing headless OpenGL for videos (render=video): $$pkgs"; \
	    export DEBIAN_FRONTEND=noninteractive; \
	    apt-get update -qq && apt-get install -y -qq --no-install-recommends $$pkgs >/dev/null; \
	  elif command -v apt-get >/dev/null 2>&1; then \
	    echo "note: videos (render=video) need headless OpenGL; install it with:"; \
	    echo "  sudo apt-get install -y $$pkgs"; \
	  else \
	    echo "note: videos (render=video) need headless OpenGL: install EGL (libEGL and Mesa) or OSMesa with your package manager"; \
	  fi; }

# JupyterLab (the `notebook` extra, installed once into .venv), opened on the comparison
# notebook; the kernel is .venv's Python. ARGS go to jupyter lab (e.g. --no-browser).
# As root (containers, this VM) jupyter refuses to start without --allow-root.
NOTEBOOK_STAMP := $(VENV)/.notebook

$(NOTEBOOK_STAMP): $(STAMP)
	@echo "installing JupyterLab into $(VENV) (once, the notebook extra; about 1 min)"
	$(PY) -m pip install --quiet -e '.[notebook]'
	touch $(NOTEBOOK_STAMP)

notebook: $(NOTEBOOK_STAMP)
	$(VENV)/bin/jupyter lab analysis/compare_runs.ipynb $$([ "$$(id -u)" = 0 ] && echo --allow-root) $(ARGS)

# the loop's speed, reported (exit 0 whatever the timings: a busy machine runs 2-3x slower);
# benchmark-check exits 1 when a speed target is missed
benchmark: $(STAMP)
	$(PY) benchmarks/loop_speed.py $(ARGS)

benchmark-check: $(STAMP)
	$(PY) benchmarks/loop_speed.py --check-targets $(ARGS)

clean:
	rm -rf $(VENV) build *.egg-info
