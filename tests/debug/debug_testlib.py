"""Helpers of the debug interface's tests: host builds of models, firmware
processes serving the debug interface on a pty, clients."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
MODELS = Path(__file__).resolve().parent / "models"

import easylab  # noqa: E402

try:
    import easylab.host_tools  # noqa: F401
except ImportError:  # a source tree where `easylab` is generator/ alone: add host_tools
    easylab.__path__.append(str(ROOT))
    import easylab.host_tools  # noqa: F401

from easylab.host_tools.debug_map import DebugMap  # noqa: E402
from easylab.host_tools.debug_protocol import DebugClient  # noqa: E402


def build(model: Path, out: Path, release: bool = False, cc: str | None = None) -> Path:
    """Build a model for the host board; returns the executable."""
    from easylab.build import build as do_build
    from easylab.frontend import lower_file

    program, result = lower_file(model)
    assert program is not None, result.report()
    return do_build(program, "host", out, release=release, cc=cc).executable


class Firmware:
    """A host firmware process serving its debug interface on a new pty."""

    def __init__(self, exe: Path, tmp: Path, *args: str, halt: bool = True, fast: bool = True,
                 duration: str | None = None, transport: str | None = None):
        self.exe = Path(exe)
        self.link = tmp / f"{self.exe.name}.pty"
        self.trace = tmp / f"{self.exe.name}.trace.csv"
        self.map_path = self.exe.parent / "debug_map.json"
        spec = transport or f"pty:{self.link}"
        cmd = [str(self.exe), "--debug", spec + (",halt" if halt else ""), "--trace", str(self.trace), *args]
        if fast:
            cmd.append("--fast")
        if duration:
            cmd += ["--duration", duration]
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if transport is None:
            deadline = time.monotonic() + 10
            while not self.link.exists():
                if self.proc.poll() is not None or time.monotonic() > deadline:
                    raise AssertionError(f"{cmd} did not start: {self.proc.communicate()}")
                time.sleep(0.01)
        self.clients: list[DebugClient] = []

    @property
    def map(self) -> DebugMap:
        return DebugMap.load(self.map_path)

    def client(self, timeout: float = 2.0) -> DebugClient:
        c = DebugClient.open(str(self.link), timeout)
        c.hello()
        self.clients.append(c)
        return c

    def wait_halted(self, client: DebugClient, timeout: float = 5.0):
        deadline = time.monotonic() + timeout
        while True:
            f = client.flags()
            if f.halted:
                return f
            assert time.monotonic() < deadline, f"not halted after {timeout} s: {f}"
            time.sleep(0.005)

    def wait_exit(self, timeout: float = 20.0) -> tuple[int, str, str]:
        out, err = self.proc.communicate(timeout=timeout)
        return self.proc.returncode, out, err

    def stop(self) -> tuple[int, str, str]:
        for c in self.clients:
            c.close()
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            out, err = self.proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            out, err = self.proc.communicate()
        return self.proc.returncode, out, err

    def rows(self) -> list[dict]:
        with open(self.trace, newline="") as f:
            return list(csv.DictReader(f))


def env_with_tools() -> dict:
    """The environment in which `python -m easylab.host_tools.debug_console` works."""
    env = dict(os.environ)
    if not _console_importable(env):
        import tempfile
        shim = Path(tempfile.mkdtemp(prefix="easylab-shim-"))
        pkg = shim / "easylab"
        pkg.mkdir(parents=True, exist_ok=True)
        (pkg / "__init__.py").write_text(
            "import os as _os\n"
            f"__path__ = [{str(ROOT / 'generator')!r}, {str(ROOT)!r}]\n"
            f"exec(compile(open(_os.path.join({str(ROOT / 'generator')!r}, '__init__.py')).read(), "
            "'easylab/__init__.py', 'exec'))\n")
        env["PYTHONPATH"] = str(shim) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _console_importable(env) -> bool:
    import sys
    proc = subprocess.run([sys.executable, "-c", "import easylab.host_tools.debug_console"], env=env,
                          capture_output=True)
    return proc.returncode == 0


# ---- fixtures (imported by the test modules: this folder has no conftest.py,
# so that no `conftest` module of ours shadows another folder's) ----

import atexit as _atexit  # noqa: E402
import functools as _functools  # noqa: E402
import shutil as _shutil  # noqa: E402
import tempfile as _tempfile  # noqa: E402

import pytest  # noqa: E402

_BUILD_ROOT = Path(_tempfile.mkdtemp(prefix="easylab-debug-builds-"))
_atexit.register(_shutil.rmtree, _BUILD_ROOT, True)


@_functools.lru_cache(maxsize=None)
def built(name: str) -> Path:
    """A debug host build of examples/NAME.elab (or models/NAME.elab), once
    per test run."""
    model = EXAMPLES / f"{name}.elab"
    if not model.exists():
        model = MODELS / f"{name}.elab"
    return build(model, _BUILD_ROOT / name)


class _Builds:
    def __getitem__(self, name: str) -> Path:
        return built(name)


@pytest.fixture
def builds():
    """builds[name] -> executable (built on first use, shared by the run)."""
    return _Builds()


@pytest.fixture
def firmware(tmp_path):
    """firmware(exe, *args, halt=True, fast=True, duration=None): started
    processes are stopped after the test."""
    started: list[Firmware] = []

    def start(exe, *args, **kw):
        fw = Firmware(exe, tmp_path, *args, **kw)
        started.append(fw)
        return fw

    yield start
    for fw in started:
        fw.stop()
