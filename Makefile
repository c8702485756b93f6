# EasyLab: set-up, tests and demos. `make demo` and `make test` do all the
# set-up themselves on a fresh Debian machine (root, apt and PyPI reachable).

PYTHON  ?= python3
VENV    ?= .venv
PY      := $(VENV)/bin/python
EASYLAB := $(VENV)/bin/easylab
BOARD   ?= host
MODEL   ?= examples/pt100_sensor.elab

# Debian packages the project uses: cross compilers and simulators for the
# boards, Modbus peers, fuzzing and sanitizer runtimes, Graphviz, tmux.
DEB_PACKAGES := gcc make pkg-config graphviz tmux socat \
	gcc-avr avr-libc binutils-avr simavr libsimavr-dev libelf-dev avrdude \
	sdcc sdcc-libraries sdcc-ucsim gputils gpsim \
	mbpoll libmodbus-dev clang libclang-rt-14-dev clang-tidy valgrind

.PHONY: setup deps venv test demo bench clean help

help:
	@echo "make setup   install Debian packages (when missing) and the virtual environment"
	@echo "make test    run the test suite (does set-up first)"
	@echo "make demo    build and run the PT100 sensor on the host board, check, analyse and draw the examples"
	@echo "make bench   run the benchmarks, results in bench/results/"
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

clean:
	rm -rf build bench/results $(VENV) *.egg-info .pytest_cache
	find . -name __pycache__ -type d -prune -exec rm -rf {} +
