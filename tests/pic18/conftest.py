"""Session fixtures of the PIC18 tests: each build made once (two at a
time: sdcc and the harness build are separate processes), in the session's
shared build cache."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from pic18_testlib import MODELS, pic18_build
from firmware_builds import build


@pytest.fixture(scope="session")
def drivers(build_cache) -> dict:
    """tests/pic18/models/drivers.elab: its PIC18F4520 release simulation
    build ("pic18") and its host program ("host")."""
    model = MODELS / "drivers.elab"
    with ThreadPoolExecutor(max_workers=2) as pool:
        pic = pool.submit(build_cache.get, ("pic18-drivers",),
                          lambda out: pic18_build(model, out, "--sim", "--release"))
        host = pool.submit(build_cache.get, ("host-drivers",), lambda out: build(model, "host", out))
        return {"pic18": pic.result(), "host": host.result()}


@pytest.fixture(scope="session")
def blink_4620(build_cache):
    """examples/blink.elab for the PIC18F4620, a debug simulation build (the
    conformance suite's build)."""
    return build_cache.example("pic18", "blink", "--mcu", "pic18f4620", "--sim")


@pytest.fixture(scope="session")
def host_blink(build_cache) -> Path:
    return build_cache.example("host", "blink").executable
