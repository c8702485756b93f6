"""Fixtures every suite may use."""

from __future__ import annotations

import pytest

from firmware_builds import BuildCache


@pytest.fixture(scope="session")
def build_cache(tmp_path_factory) -> BuildCache:
    """Firmware built once per test process, shared by the suites."""
    return BuildCache(tmp_path_factory.mktemp("builds"))
