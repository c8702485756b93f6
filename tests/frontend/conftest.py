"""Shared helpers of the front-end tests: model files in tmp_path, the CLI."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from easylab.pipeline import check_file
from firmware_builds import write_model

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def check_model(tmp_path):
    """check_model(text, files={...}) writes model.elab (and other files
    beside it) to tmp_path and checks it; returns (result, model path)."""

    def run(text: str, files: dict[str, str] | None = None, name: str = "model.elab"):
        path = write_model(tmp_path, text, files, name)
        return check_file(path), path

    return run


@pytest.fixture
def cli():
    """cli(*args, cwd=...) runs ``python -m easylab ARGS`` with this
    interpreter and the environment the tests run in (its PYTHONPATH, so an
    uninstalled tree works too); returns the CompletedProcess."""

    def run(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "easylab", *map(str, args)], capture_output=True,
                              text=True, cwd=cwd or ROOT, env=dict(os.environ), timeout=120,
                              stdin=subprocess.DEVNULL)

    return run
