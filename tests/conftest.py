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


_file_seconds: dict[str, float] = {}


def pytest_runtest_logreport(report):
    """Every test's setup, call and teardown, summed per file (on the
    controller of ``pytest -n``, which receives every worker's reports)."""
    path = report.nodeid.split("::", 1)[0]
    _file_seconds[path] = _file_seconds.get(path, 0.0) + report.duration


def pytest_sessionfinish(session, exitstatus):
    """After a run of the whole suite (no file or -k named), the seconds of
    every file in build/test-durations.json, for tests/durations.py."""
    import json

    from durations import RECORD

    config = session.config
    if hasattr(config, "workerinput") or not _file_seconds or config.getoption("keyword") or \
            any("::" in a or a.endswith(".py") for a in config.args):
        return
    previous = {}
    try:
        previous = json.loads(RECORD.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        pass
    merged = {**(previous if isinstance(previous, dict) else {}),
              **{k: round(v, 1) for k, v in _file_seconds.items()}}
    RECORD.parent.mkdir(parents=True, exist_ok=True)
    RECORD.write_text(json.dumps(dict(sorted(merged.items())), indent=1) + "\n", encoding="utf-8")
