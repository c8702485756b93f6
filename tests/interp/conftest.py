"""Fixtures of the local-execution tests: a plug-in cache of the session,
and host firmware built once per model (in parallel)."""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from interp_testlib import build_host


@pytest.fixture(scope="session", autouse=True)
def plugin_cache(tmp_path_factory) -> Path:
    """Every test (and every `easylab run` it starts) uses one fresh cache."""
    path = tmp_path_factory.mktemp("plugin_cache")
    previous = os.environ.get("EASYLAB_CACHE")
    os.environ["EASYLAB_CACHE"] = str(path)
    yield path
    if previous is None:
        os.environ.pop("EASYLAB_CACHE", None)
    else:
        os.environ["EASYLAB_CACHE"] = previous


@pytest.fixture(scope="session")
def host_firmware(tmp_path_factory):
    """firmware(model_path) -> the host executable, built on first use;
    ``firmware.prebuild(paths)`` builds several at once."""
    root = tmp_path_factory.mktemp("host_firmware")
    built: dict[Path, Path] = {}

    def firmware(model: Path) -> Path:
        if model not in built:
            built[model] = build_host(model, root / f"{model.stem}_{len(built)}")
        return built[model]

    def prebuild(models) -> None:
        todo = [m for m in dict.fromkeys(models) if m not in built]
        with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
            paths = list(pool.map(lambda ik: build_host(ik[1], root / f"{ik[1].stem}_p{ik[0]}"), enumerate(todo)))
        built.update(zip(todo, paths))

    firmware.prebuild = prebuild
    return firmware
