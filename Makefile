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
# Chromium with its driver for the service panel's browser tests.
DEB_PACKAGES := gcc make pkg-config graphviz tmux socat \
	gcc-avr avr-libc binutils-avr simavr libsimavr-dev libelf-dev avrdude \
	sdcc sdcc-libraries sdcc-ucsim gputils gpsim \
	mbpoll libmodbus-dev clang libclang-rt-14-dev clang-tidy valgrind gtkwave \
	chromium chromium-driver

.PHONY: setup deps venv test demo bench clean help flash sim

help:
	@echo "make setup   install Debian packages (when missing) and the virtual environment"
	@echo "make test    run the test suite (does set-up first)"
	@echo "make demo    check, analyse and draw the shipped example models"
	@echo "make bench   run the benchmarks, results in bench/results/"
	@echo "make flash BOARD=avr MODEL=m.elab PORT=/dev/ttyACM0 [MCU=atmega2560] [PROGRAMMER=..]  build and burn (avrdude)"
	@echo "make sim   BOARD=avr MODEL=m.elab [MCU=..] [STIMULUS=s.csv] [TRACE=t.csv] [DURATION=10s]  run in simavr"
	@echo "make clean   remove build outputs and the virtual environment"

setup: deps venv

# Installs only what is missing; costs one dpkg-query when all is there.
deps:
	@missing=$$(for p in $(DEB_PACKAGES); do \
		dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; \
	done); \
	if [ -n "$$missing" ]; then \
		echo "Installing Debian packages:" $$missing; \
		SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		$$SUDO apt-get update -qq && \
		DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq --no-install-recommends $$missing >/dev/null; \
	fi

venv: $(VENV)/.installed

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade "pip>=23" "setuptools>=64" wheel
	$(PY) -m pip install -q -e ".[test]"
	touch $@

test: setup
	$(PY) -m pytest -q

demo: setup
	$(PY) -m easylab.demo

bench: setup
	$(PY) bench/run.py

# ---- The AVR board (docs/boards.md): flash with avrdude, simulate in simavr.
# `make -n flash ...` shows the exact avrdude command. The part names and
# programmers mirror boards/avr/board.toml: the Uno's bootloader speaks the
# "arduino" protocol, the Mega 2560's the "wiring" one.
MCU         ?= atmega328p
PROGRAMMER  ?= $(if $(filter atmega2560,$(MCU)),wiring,arduino)
UPLOAD_BAUD ?= 115200
AVR_PART    := $(if $(filter atmega2560,$(MCU)),m2560,$(if $(filter atmega328p,$(MCU)),m328p,$(MCU)))
MODEL_NAME  := $(shell sed -n 's/^[[:space:]]*model[[:space:]][[:space:]]*\([A-Za-z_][A-Za-z0-9_]*\).*/\1/p' $(MODEL) 2>/dev/null | head -n 1)
BUILD_FLAGS ?=
FLASH_DIR   := build/flash/$(MODEL_NAME)-$(MCU)
SIM_DIR     := build/sim/$(MODEL_NAME)-$(MCU)
SIM_UARTS   := $(if $(filter atmega2560,$(MCU)),0 1 2 3,0)
SIM_ARGS    ?= $(foreach u,$(SIM_UARTS),--uart$(u) pty:$(SIM_DIR)/uart$(u)) \
	$(if $(STIMULUS),--stimulus $(STIMULUS)) $(if $(TRACE),--trace $(TRACE)) $(if $(DURATION),--duration $(DURATION))

flash: setup
	$(if $(filter avr,$(BOARD)),,$(error make flash: only BOARD=avr can be flashed))
	$(if $(PORT),,$(error make flash: give the board's serial port, e.g. PORT=/dev/ttyACM0))
	$(if $(MODEL_NAME),,$(error make flash: MODEL=$(MODEL) has no model line))
	$(EASYLAB) build $(MODEL) --board avr --mcu $(MCU) -o $(FLASH_DIR) $(BUILD_FLAGS)
	avrdude -p $(AVR_PART) -c $(PROGRAMMER) -P $(PORT) -b $(UPLOAD_BAUD) -D -U flash:w:$(FLASH_DIR)/$(MODEL_NAME).hex:i

sim: setup
	$(if $(filter avr,$(BOARD)),,$(error make sim: only BOARD=avr has a simulator))
	$(if $(MODEL_NAME),,$(error make sim: MODEL=$(MODEL) has no model line))
	$(EASYLAB) build $(MODEL) --board avr --mcu $(MCU) --sim -o $(SIM_DIR) $(BUILD_FLAGS)
	$(SIM_DIR)/$(MODEL_NAME)-sim $(SIM_ARGS)

clean:
	rm -rf build bench/results $(VENV) *.egg-info .pytest_cache
	find . -name __pycache__ -type d -prune -exec rm -rf {} +
