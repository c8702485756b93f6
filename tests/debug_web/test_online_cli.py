"""`easylab-debug web`'s command line: what it cannot use is refused in one
line (`easylab-debug web: error: ...`), exit status 2, never a traceback;
SIGTERM ends it with status 0."""

from __future__ import annotations

import socket
import subprocess
import sys

import pytest

from debug_testlib import ROOT, builds  # noqa: F401 (fixture)
from onlinelib import MODEL


def web(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "easylab.host_tools.debug_console", "web", *args],
                          capture_output=True, text=True, timeout=60, cwd=ROOT, stdin=subprocess.DEVNULL)


@pytest.fixture
def map_path(builds):
    return str(builds["pneumatic_cylinder"].parent / "debug_map.json")


@pytest.mark.parametrize("args,words", [
    (["--listen", "nowhere"], "give ADDR:PORT"),
    (["--listen", "example.com:80"], "is not an IP address"),
    (["--token", "short"], "--token: give 8 to 128 characters"),
    (["--model", "no/such/model.elab"], "--model no/such/model.elab: no such file"),
])
def test_what_it_cannot_use_is_refused_in_one_line(map_path, args, words):
    proc = web("--map", map_path, "/dev/null", *args)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith("easylab-debug web: error: ") and words in proc.stderr, proc.stderr
    assert "Traceback" not in proc.stderr and proc.stderr.count("\n") == 1


def test_a_map_that_is_not_one_is_refused(tmp_path):
    bad = tmp_path / "debug_map.json"
    bad.write_text('{"format": "something else"}')
    proc = web("--map", str(bad), "/dev/null")
    assert proc.returncode == 2 and proc.stderr.startswith("easylab-debug web: error: "), proc.stderr
    assert "Traceback" not in proc.stderr


def test_a_port_in_use_is_refused(map_path):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        proc = web("--map", map_path, "/dev/null", "--model", str(MODEL), "--listen", f"127.0.0.1:{port}")
    assert proc.returncode == 2 and "the port is in use" in proc.stderr, proc.stderr


def test_the_console_still_takes_its_own_arguments(map_path):
    """`web` is a word of its own: a console command line is the console's."""
    proc = subprocess.run([sys.executable, "-m", "easylab.host_tools.debug_console", "--map", map_path, "/dev/null/x",
                           "-c", "info"], capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert proc.returncode == 1 and proc.stderr.startswith("easylab-debug: error: cannot open"), proc.stderr
