# The README's two commands: `make demo` and `make test`. Each sets itself up on a fresh machine.
PY ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-slow lint typecheck docs docs-check bench clean install

# Three distributions, one import namespace `pltf` (spec/ -> pltf.spec, clients/pltf_client/ -> pltf.client, the
# toolkit's folders -> pltf.*; see setup.py). mypy cannot run setuptools' editable import hooks, so it reads the
# namespace through a tree of links in the venv (NSTREE).
NSTREE := $(VENV)/namespace/pltf
NSLINKS := spec:spec client:clients/pltf_client reference_server:reference_server fake_hardware:fake_hardware \
	conformance_tests:conformance_tests fuzz:fuzz stubgen:clients/stubgen cli:pltf_cli fixtures:fixtures zoo:zoo

$(STAMP): pyproject.toml setup.py spec/pyproject.toml clients/pyproject.toml $(wildcard reference_server/world/*.c)
	@test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ./spec -e ./clients -e '.[dev]'
	@rm -rf $(NSTREE) && mkdir -p $(NSTREE)
	@for l in $(NSLINKS); do ln -s "$(CURDIR)/$${l#*:}" "$(NSTREE)/$${l%%:*}"; done
	@touch $(STAMP)

install: $(STAMP)

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/mypy
	$(BIN)/python -m pltf.spec.docgen --check
	$(BIN)/python -m pytest -q -m "not slow"

test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -m slow

lint: $(STAMP)
	$(BIN)/ruff check .

typecheck: $(STAMP)
	$(BIN)/mypy

docs: $(STAMP)
	$(BIN)/python -m pltf.spec.docgen

docs-check: $(STAMP)
	$(BIN)/python -m pltf.spec.docgen --check

bench: $(STAMP)
	$(BIN)/python -m benchmarks --json benchmarks/results.json

demo: $(STAMP)
	$(BIN)/python -m pltf.cli.demo

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache
