"""Session fixtures of the native tests: each example built once per
configuration (compilers run in parallel threads)."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from native_testlib import EXAMPLES, SANITIZE, build


@pytest.fixture(scope="session")
def sanitized(tmp_path_factory) -> dict[str, Path]:
    """example name -> its host program built with ASan and UBSan (the
    sanitizers abort at the first error: -fno-sanitize-recover=all)."""
    root = tmp_path_factory.mktemp("examples_asan")
    with ThreadPoolExecutor(max_workers=2) as pool:
        futures = {p.stem: pool.submit(build, p, root / p.stem, cflags=SANITIZE) for p in EXAMPLES}
        return {name: f.result() for name, f in futures.items()}


# How long each example runs against data/<example>.stimulus.csv (virtual time).
DURATIONS = {"blink": "3s", "cd_to_dat": "200ms", "line_follower": "1s", "pneumatic_cylinder": "3600ms",
             "pt100_sensor": "5s"}


@pytest.fixture(scope="session")
def example_runs(sanitized, tmp_path_factory):
    """example name -> Run of its sanitized build against its stimulus in
    data/ (an example without one gets data/empty.stimulus.csv), --fast.
    Runs lazily, once per example."""
    from native_testlib import DATA, run

    root = tmp_path_factory.mktemp("example_runs")
    cache = {}

    def get(name: str):
        if name not in cache:
            stim = DATA / f"{name}.stimulus.csv"
            if not stim.exists():
                stim = DATA / "empty.stimulus.csv"
            cache[name] = run(sanitized[name], root / f"{name}.trace.csv", duration=DURATIONS.get(name, "2s"),
                              stimulus=stim)
        return cache[name]

    return get
