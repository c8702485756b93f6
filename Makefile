# EasyLab: set-up, tests and demos. `make demo` and `make test` do all the
# set-up themselves on a fresh Debian machine (root, apt and PyPI reachable).

PYTHON  ?= python3
VENV    ?= .venv
PY      := $(VENV)/bin/python
EASYLAB := $(VENV)/bin/easylab
BOARD   ?= host
MODEL   ?= examples/pt100_sensor.elab

# Debian packages the project uses: cross compilers and simulators for the
# boards, Modbus peers, fuzzing and sanitizer runtimes, Graphviz, tmux, and
# Chromium with its driver for the service panel's browser tests, Eclipse
# Cyclone DDS (libddsc, idlc in its tools) for the PC nodes' DDS exports,
# Node.js for the VS Code extension (`make vsix`) and its tests (npm: see
# the npm target).
# (The PIC18 board's sdcc with the pic16 port is built from Debian's source
# by boards/pic18/toolchain/build.sh: `make setup` runs it once.)
DEB_PACKAGES := gcc make pkg-config graphviz tmux socat \
	gcc-avr avr-libc binutils-avr simavr libsimavr-dev libelf-dev avrdude \
	sdcc sdcc-libraries sdcc-ucsim gputils gpsim gpsim-dev libglib2.0-dev g++ dpkg-dev \
	mbpoll libmodbus-dev clang libclang-rt-14-dev clang-tidy valgrind gtkwave \
	chromium chromium-driver \
	cyclonedds-dev cyclonedds-tools \
	nodejs

.PHONY: vsix vscode-packages npm fuzz mutations crosscheck-tally setup deps venv toolchains test demo bench clean help flash sim crosscheck

help:
	@echo "make setup   install Debian packages (when missing) and the virtual environment"
	@echo "make test    run the test suite (does set-up first)"
	@echo "make demo    build the PT100 smart sensor for the host board and run it"
	@echo "make bench   run the benchmarks, results in bench/results/ and docs/benchmarks.md"
	@echo "make crosscheck N=100 BOARDS=host,avr,pic18 [SEED=1000] [JOBS=2]"
	@echo "             back-to-back testing: N random models per part, every mode against local execution"
	@echo "             (modes: host avr avr328 pic18 f16 remote-host remote-avr; docs/testing.md)"
	@echo "make mutations N=10000 [SEED=1] [JOBS=2]"
	@echo "             mutated examples through the checker, the accepted ones through a host build"
	@echo "make fuzz [FUZZ_RUNS=10000000]"
	@echo "             every libFuzzer target to FUZZ_RUNS executions, figures in build/fuzz/figures.md"
	@echo "make flash BOARD=avr MODEL=m.elab PORT=/dev/ttyACM0 [MCU=..] [PROGRAMMER=..] [BUILD_FLAGS=--release]"
	@echo "             build and burn with the board's programmer (\`make -n flash ...\` shows the commands;"
	@echo "             BOARD=pic18: a PICkit on USB, PORT=usb)"
	@echo "make sim   BOARD=avr MODEL=m.elab [MCU=..] [STIMULUS=s.csv] [TRACE=t.csv] [DURATION=10s]"
	@echo "             build and run in the board's simulator, serial links on ptys in the build folder"
	@echo "make vsix    the VS Code extension (editors/vscode) as build/easylab-elab-VERSION.vsix"
	@echo "make clean   remove build outputs and the virtual environment"
	@echo "Boards: $(EASYLAB) boards (EASYLAB_BOARD_PATH adds folders of your own)"

setup: deps venv toolchains

# Toolchains built from source once into ~/.cache/easylab/ (a stamp file
# makes a second run a no-op; the script shows its log only on failure).
toolchains: deps
	@boards/pic18/toolchain/build.sh

# Installs only what is missing; costs one dpkg-query when all is there.
deps:
	@missing=$$(for p in $(DEB_PACKAGES); do \
		dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; \
	done); \
	if [ -n "$$missing" ]; then \
		echo "Installing Debian packages:" $$missing; \
		SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		$$SUDO apt-get update -qq && \
		DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq -o DPkg::Lock::Timeout=600 \
			--no-install-recommends $$missing >/dev/null; \
	fi

venv: $(VENV)/.installed

# pip's and setuptools' chatter goes to a log, shown only when the
# install fails.
$(VENV)/.installed: pyproject.toml setup.py
	@echo "Installing the virtual environment in $(VENV)/ (log: $(VENV)/install.log)"
	@$(PYTHON) -m venv $(VENV)
	@{ $(PY) -m pip install --upgrade "pip>=23" "setuptools>=64" wheel && \
	   $(PY) -m pip install -e ".[test]"; } > $(VENV)/install.log 2>&1 || \
	   { cat $(VENV)/install.log; echo "make: installing the virtual environment failed"; exit 1; }
	@touch $@

# Test processes (pytest-xdist): one per core by default (one more was
# measured no faster: the suite keeps the cores busy); TEST_JOBS=0 runs
# the suite in this process. A test module stays in one process (module
# fixtures build once); firmware several modules need is built once per run.
# Files start longest first (tests/durations.json; refresh it with
# `python tests/durations.py LOG` from a run's --durations report).
TEST_JOBS ?= auto

# The suite starts thousands of Python processes: keep their bytecode (in
# build/pycache) even where the environment says not to write it, or each
# process compiles every module it imports again.
test bench: export PYTHONDONTWRITEBYTECODE =
test bench: export PYTHONPYCACHEPREFIX = $(CURDIR)/build/pycache

# Tests marked `realtime` (a host answering a simulated board's deadlines
# against the wall clock) run alone afterwards: parallel tests would starve them.
test: setup
	$(PY) -m pytest -q -n $(TEST_JOBS) --dist loadfile --no-loadscope-reorder --durations=60 -m "not realtime"
	$(PY) -m pytest -q -n 0 -m realtime

demo: setup
	$(PY) -m easylab.demo

# The VS Code extension (docs/editors.md): its npm packages as
# package-lock.json pins them (install scripts skipped: none is needed),
# then vsce packs the grammar, configuration, client and the client's
# runtime packages.
VSCODE_EXT := editors/vscode

# Debian's nodejs comes without npm (its own package); other builds of
# nodejs bring it and conflict with Debian's: install it only when missing.
npm: deps
	@command -v npm >/dev/null || { SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq -o DPkg::Lock::Timeout=600 \
			--no-install-recommends npm >/dev/null; }
VSCODE_PACKAGES := $(VSCODE_EXT)/node_modules/.installed

vscode-packages: $(VSCODE_PACKAGES)

$(VSCODE_PACKAGES): $(VSCODE_EXT)/package-lock.json | npm
	@cd $(VSCODE_EXT) && npm ci --no-audit --no-fund --ignore-scripts --loglevel=error
	@touch $@

VSIX_VERSION = $(shell node -p "require('./$(VSCODE_EXT)/package.json').version")

vsix: vscode-packages
	@mkdir -p build
	@cd $(VSCODE_EXT) && npx --no-install vsce package --skip-license --allow-missing-repository \
		-o ../../build/easylab-elab-$(VSIX_VERSION).vsix
	@echo build/easylab-elab-$(VSIX_VERSION).vsix

bench: setup
	$(PY) bench/run.py

# Back-to-back testing on random models (docs/testing.md): findings and
# traces in build/crosscheck/, the tally per mode on the last lines. Every
# result goes to the campaign's ledger too (LEDGER=, the project's own by
# default), and a seed it already holds is not compared again;
# `make crosscheck-tally` prints the ledger's figures.
N      ?= 20
BOARDS ?= host,avr
SEED   ?= 1000
JOBS   ?= 2
LEDGER ?= tests/crosscheck/ledger.jsonl
crosscheck: setup
	$(PY) tests/crosscheck/crosscheck.py -n $(N) --boards $(BOARDS) --seed $(SEED) --jobs $(JOBS) --out build/crosscheck --ledger $(LEDGER)

crosscheck-tally: setup
	$(PY) tests/crosscheck/crosscheck.py --tally $(LEDGER)

# ---- Flashing and simulating, for any board (docs/boards.md). The board
# says which MCU is its default, how it is flashed and how its simulator
# runs (`easylab flash --print`, `easylab sim --print`); `make -n flash ...`
# shows the exact commands.
MODEL_NAME   = $(shell sed -n 's/^[[:space:]]*model[[:space:]][[:space:]]*\([A-Za-z_][A-Za-z0-9_]*\).*/\1/p' $(MODEL) 2>/dev/null | head -n 1)
MCU_NAME     = $(or $(MCU),$(shell $(EASYLAB) boards --default-mcu $(BOARD)))
MCU_FLAG     = $(if $(MCU_NAME),--mcu $(MCU_NAME))
TARGET_NAME  = $(MODEL_NAME)$(if $(MCU_NAME),-$(MCU_NAME),-$(BOARD))
BUILD_FLAGS ?=
FLASH_DIR    = build/flash/$(TARGET_NAME)
SIM_DIR      = build/sim/$(TARGET_NAME)
FLASH_FLAGS  = $(if $(PROGRAMMER),--programmer $(PROGRAMMER)) $(if $(UPLOAD_BAUD),--baud $(UPLOAD_BAUD))
SIM_ARGS    ?= $(if $(STIMULUS),--stimulus $(STIMULUS)) $(if $(TRACE),--trace $(TRACE)) \
	$(if $(DURATION),--duration $(DURATION))

flash: setup
	$(if $(PORT),,$(error make flash: give the board's serial port, e.g. PORT=/dev/ttyACM0))
	$(if $(MODEL_NAME),,$(error make flash: MODEL=$(MODEL) has no model line))
	$(EASYLAB) build $(MODEL) --board $(BOARD) $(MCU_FLAG) -o $(FLASH_DIR) $(BUILD_FLAGS)
	$(or $(shell $(EASYLAB) flash $(MODEL) --board $(BOARD) $(MCU_FLAG) --port $(PORT) -o $(FLASH_DIR) $(FLASH_FLAGS) --print),$(error make flash: board $(BOARD) gives no flash command))

sim: setup
	$(if $(MODEL_NAME),,$(error make sim: MODEL=$(MODEL) has no model line))
	$(EASYLAB) build $(MODEL) --board $(BOARD) $(MCU_FLAG) --sim -o $(SIM_DIR) $(BUILD_FLAGS)
	$(or $(shell $(EASYLAB) sim $(MODEL) --board $(BOARD) $(MCU_FLAG) -o $(SIM_DIR) --print),$(error make sim: board $(BOARD) has no simulator)) $(SIM_ARGS)

clean:
	rm -rf build bench/results $(VENV) *.egg-info .pytest_cache editors/vscode/node_modules
	find . -name __pycache__ -type d -prune -exec rm -rf {} +

# The mutation campaign (docs/testing.md, "Mutated models"): N mutants of
# the examples through the checker, the accepted ones through a host build.
mutations: setup
	$(PY) tests/frontend/mutation_campaign.py -n $(N) --seed $(SEED) --jobs $(JOBS) --out build/mutations

# Every libFuzzer target (fuzz/) to 10^7 executions under ASan and UBSan;
# figures in build/fuzz/figures.md (docs/testing.md, "Fuzzing").
FUZZ_RUNS ?= 10000000
fuzz: setup
	rm -f build/fuzz/figures.md
	EASYLAB_FUZZ_RUNS=$(FUZZ_RUNS) $(PY) -m pytest -q -n $(TEST_JOBS) tests/debug/test_debug_fuzz.py tests/service/test_service_fuzz.py tests/remote/test_remote_fuzz.py
	cat build/fuzz/figures.md
