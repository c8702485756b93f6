"""Session fixtures of the AVR tests: each build made once (in parallel
threads: avr-gcc, gcc and the harness build are separate processes), in
the session's shared build cache."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from avr_testlib import EXAMPLE_NAMES


@pytest.fixture(scope="session")
def sim_builds(build_cache) -> dict:
    """example name -> Built: a simulation build for the ATmega2560 (debug
    build, with its simavr harness)."""
    with ThreadPoolExecutor(max_workers=2) as pool:
        futures = {name: pool.submit(build_cache.example, "avr", name, "--mcu", "atmega2560", "--sim")
                   for name in EXAMPLE_NAMES}
        return {name: f.result() for name, f in futures.items()}


@pytest.fixture(scope="session")
def host_builds(build_cache) -> dict:
    """example name -> the host board's program."""
    with ThreadPoolExecutor(max_workers=2) as pool:
        futures = {name: pool.submit(build_cache.example, "host", name) for name in EXAMPLE_NAMES}
        return {name: Path(f.result().executable) for name, f in futures.items()}
