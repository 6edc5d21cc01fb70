# The README's two commands: `make demo` and `make test`. Each sets itself up on a fresh machine.
PY ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

SUDO := $(if $(filter 0,$(shell id -u)),,sudo)

.PHONY: demo test test-slow test-ray ray lint lint-native native-linters typecheck docs docs-check site bench soak clean install emulator gui chromium tshark

# The GUI's front end (gui/web, TypeScript + vite) is built into gui/static/ with the machine's node and npm.
GUI_WEB := gui/web
GUI_MODULES := $(GUI_WEB)/node_modules/.installed
GUI_BUILT := gui/static/index.html
GUI_SOURCES := $(shell find $(GUI_WEB)/src -type f 2>/dev/null) $(GUI_WEB)/index.html $(GUI_WEB)/vite.config.ts \
	$(GUI_WEB)/tsconfig.json $(wildcard clients/generated/typescript/src/*.ts)

# Three distributions, one import namespace `pltf` (spec/ -> pltf.spec, clients/pltf_client/ -> pltf.client, the
# toolkit's folders -> pltf.*; see setup.py). mypy cannot run setuptools' editable import hooks, so it reads the
# namespace through a tree of links in the venv (NSTREE). The tree's empty pltf/__init__.pyi is for mypy alone: in
# namespace mode mypy lets a folder shadow a module of the same name when no __init__ is found all the way up
# (python/mypy#13663), so pltf.spec.errata would be the data folder spec/errata/ instead of spec/errata.py, which
# Python imports. With the marker mypy verifies the module path and picks errata.py as Python does.
NSTREE := $(VENV)/namespace/pltf
NSLINKS := spec:spec client:clients/pltf_client reference_server:reference_server fake_hardware:fake_hardware \
	conformance_tests:conformance_tests fuzz:fuzz stubgen:clients/stubgen cli:pltf_cli fixtures:fixtures gui:gui zoo:zoo proxy:proxy harness:harness

$(STAMP): pyproject.toml setup.py spec/pyproject.toml clients/pyproject.toml $(wildcard reference_server/world/*.c) $(wildcard proxy/*.c) $(wildcard fuzz/*.c)
	@test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ./spec -e ./clients -e '.[dev]'
	@rm -rf $(NSTREE) && mkdir -p $(NSTREE)
	@for l in $(NSLINKS); do ln -s "$(CURDIR)/$${l#*:}" "$(NSTREE)/$${l%%:*}"; done
	@touch $(NSTREE)/__init__.pyi
	@touch $(STAMP)

install: $(STAMP) $(GUI_BUILT)

# tshark (Debian's package) runs the generated Wireshark dissector (proxy/pltf.lua) in tests/proxy and
# benchmarks/bench_proxy.py. Idempotent: installed once, found on PATH afterwards.
tshark:
	@command -v tshark >/dev/null 2>&1 || { $(SUDO) apt-get update -qq && \
		$(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq tshark; }

$(GUI_MODULES): $(GUI_WEB)/package.json $(GUI_WEB)/package-lock.json
	cd $(GUI_WEB) && npm ci --no-audit --no-fund
	@touch $@

$(GUI_BUILT): $(GUI_MODULES) $(GUI_SOURCES)
	cd $(GUI_WEB) && npm run build

gui: $(GUI_BUILT)

# tests/proxy/test_mcap_export.py reads the exported MCAP a second time with @mcap/core (npm), as Foxglove does.
MCAP_READER := tests/proxy/mcap_reader
MCAP_MODULES := $(MCAP_READER)/node_modules/.installed
$(MCAP_MODULES): $(MCAP_READER)/package.json $(MCAP_READER)/package-lock.json
	cd $(MCAP_READER) && npm ci --no-audit --no-fund
	@touch $@

# The browser tests drive Debian's chromium (tests/gui); CI runs as root and reaches Debian's packages.
chromium:
	@command -v chromium >/dev/null 2>&1 || (apt-get update -qq && apt-get install -y -qq chromium)

# The emulator is built first and its tests may not skip (PLTF_REQUIRE_EMULATOR=1, tests/emulator_gate.py): without
# Go make test fails at the build, not by quietly skipping the emulator's checks.
test: $(STAMP) $(GUI_BUILT) $(MCAP_MODULES) chromium tshark emulator
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(MAKE) --no-print-directory lint-native
	$(BIN)/mypy
	$(BIN)/lint-imports --no-cache
	$(BIN)/python -m pltf.spec.docgen --check
	$(BIN)/python -m pltf.gui.specgen --check
	$(BIN)/python -m pltf.proxy.dissector --check
	$(BIN)/python docs/gen/architecture.py --check
	$(MAKE) --no-print-directory site
	cd $(GUI_WEB) && npm test --silent
	PLTF_REQUIRE_EMULATOR=1 $(BIN)/python -m pytest -q -m "not slow and not ray" -n 2 --dist loadfile

test-slow: $(STAMP) tshark
	$(BIN)/python -m pytest -q -m "slow and not ray"

# Ray (an optional extra) for what runs past one machine: the tests start their own cluster on 127.0.0.1.
RAY_STAMP := $(VENV)/.ray-installed
$(RAY_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[ray]'
	@touch $(RAY_STAMP)

ray: $(RAY_STAMP)

test-ray: $(RAY_STAMP) emulator
	RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0 PLTF_REQUIRE_RAY=1 $(BIN)/python -m pytest -q -m ray -p no:xdist

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

# The languages beside Python, TypeScript, Go and Rust (ruff, biome, gofmt + go vet in tests/emulator, rustfmt in
# tests/clients): C and C++ formatted as .clang-format says (one at the root for C, clients/ and examples/ for C++)
# and compiled with every warning an error, shell scripts through shellcheck, Java formatted by google-java-format
# (AOSP style) and compiled with javac -Xlint:all -Werror. Generated per-telegram tables keep the generator's layout,
# as the Rust client's per-telegram modules are #[rustfmt::skip]: C++ marks them `// clang-format off`; Java has no
# such marker, so Protocol.java is left to the generator (tests/clients holds it to the spec).
GJF_VERSION := 1.28.0
GJF := $(VENV)/share/java/google-java-format-$(GJF_VERSION)-all-deps.jar
GJF_RUN := java $(foreach p,api code file parser tree util,--add-exports=jdk.compiler/com.sun.tools.javac.$(p)=ALL-UNNAMED) -jar $(GJF) --aosp
C_SOURCES := $(shell git ls-files '*.c' 2>/dev/null)
CXX_SOURCES := $(shell git ls-files '*.cpp' 2>/dev/null)
SH_SOURCES := $(shell git ls-files '*.sh' 2>/dev/null)
JAVA_SOURCES := $(shell git ls-files '*.java' 2>/dev/null)
PY_INCLUDE = $(shell $(BIN)/python -c 'import sysconfig; print(sysconfig.get_paths()["include"])')

native-linters:
	@command -v clang-format >/dev/null 2>&1 && command -v shellcheck >/dev/null 2>&1 || { $(SUDO) apt-get update -qq && \
		$(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq clang-format shellcheck; }

$(GJF):
	mvn -q dependency:copy -Dartifact=com.google.googlejavaformat:google-java-format:$(GJF_VERSION):jar:all-deps \
		-DoutputDirectory=$(dir $(GJF))

lint-native: $(STAMP) native-linters $(GJF)
	clang-format --dry-run --Werror $(C_SOURCES) $(CXX_SOURCES) $(shell git ls-files '*.hpp' 2>/dev/null)
	@for f in $(C_SOURCES); do gcc -std=gnu11 -fsyntax-only -Wall -Wextra -Werror -pthread -I$(PY_INCLUDE) $$f || exit 1; done
	@for f in $(CXX_SOURCES); do g++ -std=c++17 -fsyntax-only -Wall -Wextra -Werror -Iclients/generated/cpp/include $$f \
		|| exit 1; done
	shellcheck $(SH_SOURCES)
	$(GJF_RUN) --dry-run --set-exit-if-changed $(filter-out %/Protocol.java,$(JAVA_SOURCES))
	@out=$$(mktemp -d) && javac --release 17 -encoding UTF-8 -Xlint:all -Werror -d $$out $(JAVA_SOURCES) && rm -rf $$out

typecheck: $(STAMP)
	$(BIN)/mypy

docs: $(STAMP)
	$(BIN)/python -m pltf.spec.docgen
	$(BIN)/python -m pltf.proxy.dissector
	$(BIN)/python docs/gen/architecture.py
	$(MAKE) --no-print-directory site

docs-check: $(STAMP)
	$(BIN)/python -m pltf.spec.docgen --check
	$(BIN)/python -m pltf.proxy.dissector --check
	$(BIN)/python docs/gen/architecture.py --check

# The documentation site (mkdocs.yml, docs/) into site/: every warning is an error (no --quiet: it would hide them
# from --strict), then every link of the built pages, into the site and to files of the checkout, is checked.
site: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict
	$(BIN)/python docs/gen/linkcheck.py site

bench: $(STAMP) $(GUI_BUILT) chromium tshark
	$(BIN)/python -m benchmarks --json benchmarks/results.json

# An hour of the reference server at time scale 10 with the GUI in chromium, the proxy recording, the patrol and a
# reconnecting client; RSS, descriptors and threads of every process each minute (benchmarks/soak/). Not in `test`.
soak: $(STAMP) $(GUI_BUILT) chromium
	$(BIN)/python -m benchmarks.soak --out benchmarks/results/soak.md

# The Go emulator (issue 17), a second implementation of the protocol: emulator/bin/emulator.
emulator:
	sh emulator/build.sh

demo: $(STAMP)
	$(BIN)/python -m pltf.cli.demo

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache gui/static $(GUI_WEB)/node_modules $(MCAP_READER)/node_modules
