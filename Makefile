# Quick start: `make exports` builds the default tail, `make test` runs the tests.
# Both create .venv on first use (Python 3.11 and the package registries only).
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: exports test check clean

$(STAMP): pyproject.toml
	@command -v $(PYTHON) >/dev/null || { echo "needs $(PYTHON) on PATH (set PYTHON=...)"; exit 2; }
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test]'
	touch $(STAMP)

exports: $(STAMP)
	$(BIN)/bvsr build params/bvsr.toml -o exports/bvsr
	$(BIN)/bvsr check exports/bvsr

test: $(STAMP)
	$(BIN)/python -m pytest -q

clean:
	rm -rf $(VENV) exports
