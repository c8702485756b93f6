"""Fixtures of the online mode's tests (tests/debug_web): one headless
Chromium for the session, `easylab-debug web` servers stopped (and
checked) at the end of each test."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from onlinelib import Browser, OnlineServer


@pytest.fixture(scope="session")
def browser(tmp_path_factory):
    missing = [tool for tool in ("chromium", "chromedriver") if shutil.which(tool) is None]
    assert not missing, f"{' and '.join(missing)} missing: `make setup` installs Debian's chromium and chromium-driver"
    b = Browser(tmp_path_factory.mktemp("chromium"))
    yield b
    b.quit()


@pytest.fixture
def online():
    """online(map_path, target, **kw) starts `easylab-debug web`."""
    started: list[OnlineServer] = []

    def start(map_path: Path, target: str, **kw) -> OnlineServer:
        s = OnlineServer(map_path, target, **kw).start()
        started.append(s)
        return s
    yield start
    for s in started:
        s.stop()
