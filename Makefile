# The two commands of the README:
#   make run    set everything up (once) and run the default docking
#   make test   set everything up (once) and run the fast test suite
# Only Python >= 3.11 and make are needed; everything else installs into .venv.

PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: run test test-slow test-all benchmark setup clean

setup: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -c 'import sys; sys.exit("compliant-docking needs Python >= 3.11, found " + sys.version.split()[0]) if sys.version_info < (3, 11) else None'
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

run: $(STAMP)
	$(PY) -m compliant_docking $(ARGS)

test: $(STAMP)
	$(PY) -m pytest -q $(PYTEST_ARGS)

test-slow: $(STAMP)
	$(PY) -m pytest -q -m slow $(PYTEST_ARGS)

test-all: $(STAMP)
	$(PY) -m pytest -q -m 'slow or not slow' $(PYTEST_ARGS)

benchmark: $(STAMP)
	$(PY) benchmarks/loop_speed.py $(ARGS)

clean:
	rm -rf $(VENV) build *.egg-info
