"""Session fixtures of the AVR tests: each build made once (in parallel
threads: avr-gcc, gcc and the harness build are separate processes)."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from avr_testlib import EXAMPLES, avr_build, host_build


@pytest.fixture(scope="session")
def sim_builds(tmp_path_factory) -> dict:
    """example name -> Built: a simulation build for the ATmega2560 (debug
    build, with its simavr harness)."""
    root = tmp_path_factory.mktemp("avr_sim")
    with ThreadPoolExecutor(max_workers=2) as pool:
        futures = {p.stem: pool.submit(avr_build, p, root / p.stem, "--mcu", "atmega2560", "--sim")
                   for p in EXAMPLES}
        return {name: f.result() for name, f in futures.items()}


@pytest.fixture(scope="session")
def host_builds(tmp_path_factory) -> dict:
    """example name -> the host board's program."""
    root = tmp_path_factory.mktemp("avr_host_ref")
    with ThreadPoolExecutor(max_workers=2) as pool:
        futures = {p.stem: pool.submit(host_build, p, root / p.stem) for p in EXAMPLES}
        return {name: Path(f.result()) for name, f in futures.items()}
