"""Fixtures every suite may use."""

from __future__ import annotations

import pytest

from firmware_builds import BuildCache


@pytest.fixture(scope="session")
def build_cache(tmp_path_factory, worker_id) -> BuildCache:
    """Firmware built once per run, shared by the suites and by the test
    processes of ``pytest -n`` (their temporary folders share a parent)."""
    if worker_id == "master":
        return BuildCache(tmp_path_factory.mktemp("builds"))
    return BuildCache(tmp_path_factory.getbasetemp().parent / "shared-builds", private=worker_id)
