# The README's two commands: `make demo` and `make test`. Each sets itself up on a fresh machine.
PY ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-slow lint typecheck docs docs-check bench clean install

$(STAMP): pyproject.toml setup.py $(wildcard reference_server/world/*.c)
	@test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	@touch $(STAMP)

install: $(STAMP)

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/mypy
	$(BIN)/python -m spec.docgen --check
	$(BIN)/python -m pytest -q -m "not slow"

test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -m slow

lint: $(STAMP)
	$(BIN)/ruff check .

typecheck: $(STAMP)
	$(BIN)/mypy

docs: $(STAMP)
	$(BIN)/python -m spec.docgen

docs-check: $(STAMP)
	$(BIN)/python -m spec.docgen --check

bench: $(STAMP)
	$(BIN)/python -m benchmarks --json benchmarks/results.json

demo: $(STAMP)
	$(BIN)/python -m pltf_cli.demo

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache
