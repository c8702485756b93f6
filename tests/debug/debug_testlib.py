"""Helpers of the debug interface's tests: host builds of models, firmware
processes serving the debug interface on a pty, clients."""

from __future__ import annotations

import csv
import json
import os
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
from firmware_builds import end_process  # noqa: E402


def build(model: Path, out: Path, release: bool = False, cc: str | None = None) -> Path:
    """Build a model for the host board; returns the executable."""
    from easylab.build import build as do_build
    from easylab.pipeline import lower_file

    program, result = lower_file(model)
    assert program is not None, result.report()
    return do_build(program, "host", out, release=release, cc=cc).executable


def wait_halted(client: DebugClient, timeout: float = 5.0):
    """The flags of ``client``'s program once it is halted (at most ``timeout`` s)."""
    deadline = time.monotonic() + timeout
    while True:
        f = client.flags()
        if f.halted:
            return f
        assert time.monotonic() < deadline, f"not halted after {timeout} s: {f}"
        time.sleep(0.005)


def transition_halts(client: DebugClient, transitions: list[dict], rounds: int = 12, timeout: float = 3.0):
    """Breakpoints on every transition of chart 0 (``transitions``, the
    map's), then run: the flags of each halt at one, for at most ``rounds``
    halts or until none comes within ``timeout`` s (the stimulus is over)."""
    from easylab.host_tools.debug_protocol import K

    for tr in transitions:
        client.bp_set(K.P_TRANSITION, 0, tr["id"])
    for _ in range(rounds):
        client.run()
        try:
            f = wait_halted(client, timeout)
        except AssertionError:
            return
        assert f.why == "breakpoint" and f.location.kind == K.P_TRANSITION, f
        yield f


class Firmware:
    """A host firmware process serving its debug interface on a new pty."""

    start_timeout = 10.0  # seconds until the debug link exists

    def __init__(self, exe: Path, tmp: Path, *args: str, halt: bool = True, fast: bool = True,
                 duration: str | None = None, transport: str | None = None):
        self.exe = Path(exe)
        self.link = tmp / f"{self.exe.name}.pty"
        self.trace = tmp / f"{self.exe.name}.trace.csv"
        self.map_path = self.maps_dir(tmp) / "debug_map.json"
        self.starts_halted = halt
        spec = transport or f"pty:{self.link}"
        cmd = self.command(spec, halt, list(args))
        if fast:
            cmd.append("--fast")
        if duration:
            cmd += ["--duration", duration]
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if transport is None:
            deadline = time.monotonic() + self.start_timeout
            while not self.link.exists():
                if self.proc.poll() is not None or time.monotonic() > deadline:
                    raise AssertionError(f"{cmd} did not start: {self.proc.communicate()}")
                time.sleep(0.01)
        self.clients: list[DebugClient] = []

    def maps_dir(self, tmp: Path) -> Path:
        """Where the debug map of this firmware is."""
        return self.exe.parent

    def command(self, spec: str, halt: bool, args: list[str]) -> list[str]:
        return [str(self.exe), "--debug", spec + (",halt" if halt else ""), "--trace", str(self.trace), *args]

    @property
    def map(self) -> DebugMap:
        return DebugMap.load(self.map_path)

    def client(self, timeout: float = 2.0) -> DebugClient:
        """A client of the debug link; the first one of a program started
        halted returns once the program is (a process may answer before it
        reaches its first halt)."""
        c = DebugClient.open(str(self.link), timeout)
        c.hello()
        if self.starts_halted and not self.clients:
            self.wait_halted(c)
        self.clients.append(c)
        return c

    def wait_halted(self, client: DebugClient, timeout: float = 5.0):
        return wait_halted(client, timeout)

    def wait_exit(self, timeout: float = 20.0) -> tuple[int, str, str]:
        out, err = self.proc.communicate(timeout=timeout)
        return self.proc.returncode, out, err

    def stop(self) -> tuple[int, str, str]:
        for c in self.clients:
            c.close()
        out, err = end_process(self.proc, timeout=10)
        return self.proc.returncode, out, err

    def rows(self) -> list[dict]:
        with open(self.trace, newline="") as f:
            return list(csv.DictReader(f))


class McuFirmware(Firmware):
    """An MCU's firmware in its board's simulator harness, NAME-sim (the
    ATmega2560 in simavr, the PIC18F4620 in gpsim), with the model's debug
    UART on a new pty (or TCP port): the same options and the same client
    side as Firmware. `halt` is the harness's --halt, the host's
    `--debug ...,halt`."""

    def command(self, spec: str, halt: bool, args: list[str]) -> list[str]:
        hw = json.loads((self.exe.parent / "hw_map.json").read_text())
        uart = next(n for n, u in hw["uarts"].items() if u["use"] == "debug")
        return [str(self.exe), f"--uart{uart}", spec, "--trace", str(self.trace), *args] + (["--halt"] if halt else [])


class InterpFirmware(Firmware):
    """Local execution: `easylab run MODEL` (exe is the model file)
    interpreting the model and serving its debug interface on a new pty (or
    TCP port): the same options and the same client side as Firmware; the
    maps are written with --maps."""

    start_timeout = 120.0  # the first run of a model compiles its plug-ins and interfaces library

    def maps_dir(self, tmp: Path) -> Path:
        return tmp / f"{self.exe.stem}.maps"

    def command(self, spec: str, halt: bool, args: list[str]) -> list[str]:
        import sys
        return [sys.executable, "-m", "easylab", "run", str(self.exe), "--debug", spec + (",halt" if halt else ""),
                "--trace", str(self.trace), "--maps", str(self.map_path.parent), *args]


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


# The MCUs of the simulator boards the suite runs on.
SIM_MCUS = {"avr": "atmega2560", "pic18": "pic18f4620"}


@_functools.lru_cache(maxsize=None)
def built_sim(board: str, name: str) -> Path:
    """A simulation build (debug) of examples/NAME.elab (or models/NAME.elab)
    for an MCU board, once per test run (on the PIC18 its variant with the
    debug interface on uart0: firmware_builds.board_model): its harness,
    NAME-sim."""
    import subprocess as sp
    import sys
    from firmware_builds import board_model
    model = EXAMPLES / f"{name}.elab"
    if not model.exists():
        model = MODELS / f"{name}.elab"
    out = _BUILD_ROOT / board / name
    model = board_model(board, model, "debug", out / "model")
    proc = sp.run([sys.executable, "-m", "easylab", "build", str(model), "--board", board, "--mcu", SIM_MCUS[board],
                   "--sim", "-o", str(out)], capture_output=True, text=True, timeout=300, stdin=sp.DEVNULL)
    assert proc.returncode == 0, f"{board} build of {name} failed:\n{proc.stdout}{proc.stderr}"
    return next(Path(line.split(": ", 1)[1]) for line in proc.stdout.splitlines() if line.startswith("simulator: "))


# The boards the debug suite runs on: the host board's process, the AVR
# firmware (ATmega2560) in simavr and the PIC18 firmware (PIC18F4620) in
# gpsim with their debug UART on a pty, local execution. A test runs on all
# with @on_boards, on the host only with @host_only(reason).
BOARDS = ("host", "avr", "pic18", "interp")
on_boards = pytest.mark.parametrize("board", BOARDS, indirect=True)


def host_only(reason: str, interp: bool = True):
    """On the host board (and in local execution unless `interp` is False),
    the MCU boards skipped for `reason`."""
    boards = ["host"] + [pytest.param(b, marks=pytest.mark.skip(reason=f"host-only: {reason}")) for b in SIM_MCUS]
    if interp:
        boards.append("interp")
    return pytest.mark.parametrize("board", boards, indirect=True)


@pytest.fixture
def board(request) -> str:
    """The board the firmware runs on (host unless the test is parametrised;
    a module whose tests are parametrised by board imports this fixture)."""
    return getattr(request, "param", "host")


def _board_of(request) -> str:
    """The test's board: its `board` parameter, else host (modules that do
    not import the `board` fixture are host-only)."""
    cs = getattr(request.node, "callspec", None)
    return cs.params.get("board", "host") if cs is not None else "host"


# Models an MCU board cannot run at all, with why (the test is skipped).
DOES_NOT_FIT = {("pic18", "line_follower"): "line_follower drives three motors, and the PIC18F4620 has two PWM "
                                            "outputs (CCP1, CCP2); its camera needs a UART besides the debugger's, "
                                            "and the part has one EUSART"}


class _Builds:
    def __init__(self, board: str = "host"):
        self.board = board

    def __getitem__(self, name: str) -> Path:
        if (self.board, name) in DOES_NOT_FIT:
            pytest.skip(DOES_NOT_FIT[self.board, name])
        if self.board == "interp":  # local execution runs the model itself
            return EXAMPLES / f"{name}.elab" if (EXAMPLES / f"{name}.elab").exists() else MODELS / f"{name}.elab"
        return built_sim(self.board, name) if self.board in SIM_MCUS else built(name)


@pytest.fixture
def builds(request):
    """builds[name] -> executable (built on first use, shared by the run):
    the host program, or for an MCU board its simulator harness."""
    return _Builds(_board_of(request))


@pytest.fixture
def firmware(tmp_path, request):
    """firmware(exe, *args, halt=True, fast=True, duration=None): started
    processes are stopped after the test."""
    started: list[Firmware] = []
    board = _board_of(request)

    def start(exe, *args, **kw):
        kind = McuFirmware if board in SIM_MCUS else (InterpFirmware if board == "interp" else Firmware)
        fw = kind(exe, tmp_path, *args, **kw)
        started.append(fw)
        return fw

    yield start
    for fw in started:
        ended = fw.proc.poll()  # before the stop: on its own (a crash, a simulator's error)?
        status, _, err = fw.stop()
        if ended is not None and status != 0:
            print(f"{fw.exe.name} ended by itself with status {status}:\n{err}")
