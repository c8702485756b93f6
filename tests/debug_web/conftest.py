"""Fixtures of the online mode's tests (tests/debug_web): one headless
Chromium for the session, `easylab-debug web` servers stopped (and
checked) at the end of each test."""

from __future__ import annotations

from pathlib import Path

import pytest

from onlinelib import Browser, OnlineServer
from weblib import start_browser


@pytest.fixture(scope="session")
def browser(tmp_path_factory):
    b = start_browser(tmp_path_factory, Browser)
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
