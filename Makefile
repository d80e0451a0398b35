# Quick start: `make exports` builds the default tail, `make test` runs the tests.
# Both create .venv on first use (Python 3.11 and the package registries only).
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: exports test check-l clean

$(STAMP): pyproject.toml
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' || \
		{ echo "needs Python 3.11 (found $(PYTHON)); run: make PYTHON=/path/to/python3.11"; exit 2; }
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet -e '.[test,gpu,cad]'
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
