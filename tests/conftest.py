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


def pytest_collection_modifyitems(session, config, items):
    """Longest test files first (tests/durations.py): `--dist loadfile`
    hands out files in collection order, so a long file collected last
    would run alone at the end. Tests keep their order inside a file."""
    from durations import DEFAULT_SECONDS, load

    seconds = load()
    if not seconds:
        return
    items.sort(key=lambda item: -seconds.get(item.nodeid.split("::", 1)[0], DEFAULT_SECONDS))
