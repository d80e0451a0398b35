# Quick start: `make exports` builds the default tail, `make test` runs the tests.
# Both create .venv on first use (Python 3.11 to 3.13 and the package registries only), installing the
# exact tested set of requirements/lock.txt.
PYTHON ?= $(shell command -v python3.11 || command -v python3.12 || command -v python3.13 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
LOCK := requirements/lock.txt

.PHONY: exports test check-l clean

$(STAMP): pyproject.toml $(LOCK)
	@$(PYTHON) -c 'import sys; sys.exit(not (3, 11) <= sys.version_info[:2] <= (3, 13))' || \
		{ echo "needs Python 3.11, 3.12 or 3.13 (found $(PYTHON)); run: make PYTHON=/path/to/python3.12"; exit 2; }
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet -c $(LOCK) -e '.[test,gpu,cad,docs,lint]'
	$(BIN)/python -m compileall -q bvsr_cad  # as pip does for a regular install (this one is editable)
	touch $(STAMP)

exports: $(STAMP)
	$(BIN)/bvsr build params/bvsr.toml -o exports/bvsr
	$(BIN)/bvsr check exports/bvsr

check-l: $(STAMP)
	$(BIN)/bvsr build params/bvsr_l.toml -o exports/bvsr_l -q
	$(BIN)/bvsr check exports/bvsr_l -q

test: $(STAMP)
	$(BIN)/python -m pytest -q -n auto --maxprocesses 4

clean:
	rm -rf $(VENV) exports
