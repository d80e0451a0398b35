# Quick start: `make exports` builds the default tail, `make test` runs the tests.
# Both create .venv on first use (Python 3.11 to 3.13 and the package registries only), installing
# from the exact tested set of requirements/lock.txt: `make exports` the core and the checks' second
# simulator (the crosscheck extra: without it `bvsr check` skips two checks), `make test` adds what
# every test needs (the test, gpu, cad, docs and lint extras). Each step is marked done by a stamp in
# .venv, made again when pyproject.toml or the lock changes.
# The installer is uv where it is on PATH (the same lock in a fraction of pip's time), else uv
# installed into .venv by pip (at the lock's version), else pip itself.
PYTHON ?= $(shell command -v python3.11 || command -v python3.12 || command -v python3.13 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
LOCK := requirements/lock.txt
CORE_EXTRAS := crosscheck
TEST_EXTRAS := test,gpu,cad,docs,lint
CORE := $(VENV)/.installed-core
TESTS := $(VENV)/.installed-test

.PHONY: exports test test-long test-deps check-l clean

# $(call install,EXTRAS[,UV_OPTIONS]): the package, editable, with EXTRAS, at the lock's versions.
define install
	@if command -v uv >/dev/null 2>&1; then uv=uv; \
	elif [ -x $(BIN)/uv ] || $(BIN)/pip install --quiet -c $(LOCK) uv; then uv=$(BIN)/uv; \
	else uv=; fi; \
	if [ -n "$$uv" ]; then \
		echo "$$uv pip install -c $(LOCK) -e '.[$(1)]'"; \
		$$uv pip install --quiet --compile-bytecode --python $(BIN)/python -c $(LOCK) -e '.[$(1)]' $(2); \
	else \
		echo "$(BIN)/pip install -c $(LOCK) -e '.[$(1)]'"; \
		$(BIN)/pip install --quiet -c $(LOCK) -e '.[$(1)]'; \
	fi
endef

$(BIN)/python:
	@$(PYTHON) -c 'import sys; sys.exit(not (3, 11) <= sys.version_info[:2] <= (3, 13))' || \
		{ echo "needs Python 3.11, 3.12 or 3.13 (found $(PYTHON)); run: make PYTHON=/path/to/python3.12"; exit 2; }
	$(PYTHON) -m venv $(VENV)

$(CORE): pyproject.toml $(LOCK) | $(BIN)/python
	$(call install,$(CORE_EXTRAS))
	$(BIN)/python -m compileall -q bvsr_cad  # as pip does for a regular install (this one is editable)
	touch $(CORE)

# build123d's OCP without VTK (the core) and CadQuery's with it (the cad extra) are one module, OCP;
# CadQuery needs the one with VTK on disk. pip installs it after the core's; uv installs in parallel
# and promises no order, so it is told to write cadquery-ocp again.
$(TESTS): $(CORE)
	$(call install,$(TEST_EXTRAS),--reinstall-package cadquery-ocp)
	touch $(TESTS)

exports: $(CORE)
	$(BIN)/bvsr build params/bvsr.toml -o exports/bvsr
	$(BIN)/bvsr check exports/bvsr

check-l: $(CORE)
	$(BIN)/bvsr build params/bvsr_l.toml -o exports/bvsr_l -q
	$(BIN)/bvsr check exports/bvsr_l -q

# What `make test` installs, without running the tests (CI: ruff and mkdocs before the tests).
test-deps: $(TESTS)

# One worker per core (at most four); worksteal: a worker that runs out of tests takes some queued
# on another, so the whole builds do not leave one core idle at the end. pytest reads more options
# from PYTEST_ADDOPTS (CI: --durations=15, the 15 slowest tests). The tests marked long (minutes of
# CPU each: MJX compiling the tail on the quadruped) are left to make test-long, which CI runs too.
test: $(TESTS)
	$(BIN)/python -m pytest -q -n auto --maxprocesses 4 --dist worksteal -m "not long"

test-long: $(TESTS)
	$(BIN)/python -m pytest -q -m long

clean:
	rm -rf $(VENV) exports
