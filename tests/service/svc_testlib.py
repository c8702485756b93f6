"""Helpers of the service interface's tests (tests/service): firmware
processes serving Modbus TCP and RTU on ptys, raw Modbus frames."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

from sim_modbus import RawPty, crc16, rtu_frame  # noqa: F401 (the suites import them from here)

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
DATA = Path(__file__).resolve().parent / "data"

# ---------------------------------------------------------------- processes



def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def declares_modbus_tcp(exe: Path) -> bool:
    """Whether the model behind a firmware (or a model file, for local
    execution) declares `modbus tcp`."""
    if exe.suffix == ".elab":
        return any(line.lstrip().startswith("modbus tcp") for line in exe.read_text().splitlines())
    smap = exe.parent / "service_map.json"
    return smap.is_file() and "tcp" in json.loads(smap.read_text()).get("interfaces", {})


class Firmware:
    """A host firmware process serving Modbus (and optionally the HMI)."""

    def __init__(self, exe: Path, workdir: Path, tcp: bool = True, rtu: bool = True, hmi: bool = False,
                 nvram: Path | None = None, extra: list[str] | None = None, port: int | None = None):
        self.exe = exe
        self.port = (port or free_port()) if tcp else None
        self.rtu = workdir / f"rtu{id(self)}" if rtu else None
        self.hmi = workdir / f"hmi{id(self)}" if hmi else None
        self.nvram = nvram
        args = [str(exe), "--duration", "600s"]
        if tcp:
            args += ["--modbus-tcp", str(self.port)]
        elif declares_modbus_tcp(exe):
            # not used, but not the model's fixed port either: two runs at
            # once (other tests, other test processes) must not collide
            args += ["--modbus-tcp", str(free_port())]
        if rtu:
            args += ["--modbus-rtu", f"pty:{self.rtu}"]
        if hmi:
            args += ["--hmi", f"pty:{self.hmi}"]
        if nvram is not None:
            args += ["--nvram", str(nvram)]
        self.args = args + (extra or [])
        self.proc = None

    def start(self, wait: bool = True) -> "Firmware":
        env = dict(os.environ, ASAN_OPTIONS="detect_leaks=0", UBSAN_OPTIONS="print_stacktrace=1")
        self.proc = subprocess.Popen(self.args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
        if wait:
            self.wait_ready()
        return self

    def wait_ready(self, timeout: float = 10.0) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise AssertionError(f"firmware exited {self.proc.returncode}: {self.proc.stderr.read().decode()}")
            ok = True
            if self.port is not None:
                try:
                    socket.create_connection(("127.0.0.1", self.port), timeout=0.2).close()
                except OSError:
                    ok = False
            for link in (self.rtu, self.hmi):
                if link is not None and not link.exists():
                    ok = False
            if ok:
                return
            time.sleep(0.01)
        raise AssertionError("firmware did not come up")

    def stop(self) -> str:
        """SIGTERM, wait; returns stderr (checked for sanitizer reports)."""
        if self.proc is None:
            return ""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            _, err = self.proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        text = err.decode(errors="replace")
        for marker in ("runtime error", "AddressSanitizer", "LeakSanitizer"):
            assert marker not in text, text
        return text

    def kill(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()


# The MCU boards the suite runs on, with the MCU of their simulation builds.
SIM_MCUS = {"avr": "atmega2560", "pic18": "pic18f4620"}

MCU_NO_TCP = ("host-only: Modbus TCP needs a network; the MCU boards (avr, pic18) have none (they refuse "
              "`modbus tcp` at build time)")


class McuFirmware(Firmware):
    """An MCU's firmware in its board's simulator harness (NAME-sim, real
    time: the ATmega2560 in simavr, the PIC18F4620 in gpsim) serving Modbus
    RTU on the model's Modbus UART on a pty: the same `rtu` link and the
    same life cycle as Firmware. No Modbus TCP (`port` stays None), no HMI;
    `rtu_link` names the pty's link (a restart may keep it)."""

    def __init__(self, exe: Path, workdir: Path, tcp: bool = True, rtu: bool = True, hmi: bool = False,
                 nvram: Path | None = None, extra: list[str] | None = None, rtu_link: Path | None = None):
        assert not hmi, "the MCU boards have no HMI"
        assert rtu, MCU_NO_TCP
        self.exe = exe
        self.port = None
        self.rtu = rtu_link or workdir / f"rtu{id(self)}"
        self.hmi = None
        self.nvram = nvram
        hw = json.loads((Path(exe).parent / "hw_map.json").read_text())
        uart = next(n for n, u in hw["uarts"].items() if u["use"] == "modbus-rtu")
        args = [str(exe), "--duration", "600s", f"--uart{uart}", f"pty:{self.rtu}"]
        if nvram is not None:
            args += ["--nvram", str(nvram)]
        self.args = args + (extra or [])
        self.proc = None

    def wait_ready(self, timeout: float = 10.0) -> None:
        super().wait_ready(timeout)
        time.sleep(0.02)  # the link is there before the firmware has opened its UART (about 1 ms of its time)


class InterpFirmware(Firmware):
    """Local execution: `easylab run MODEL` (exe is the model file, real
    time) serving Modbus TCP and RTU like the host firmware, with the same
    options and the same life cycle. No HMI."""

    def __init__(self, exe: Path, workdir: Path, tcp: bool = True, rtu: bool = True, hmi: bool = False,
                 nvram: Path | None = None, extra: list[str] | None = None, port: int | None = None):
        import sys
        assert not hmi, "local execution has no HMI"
        super().__init__(exe, workdir, tcp, rtu, False, nvram, extra, port)
        self.args = [sys.executable, "-m", "easylab", "run", str(exe), *self.args[1:],
                     "--maps", str(workdir / f"maps{id(self)}")]

    def wait_ready(self, timeout: float = 120.0) -> None:
        super().wait_ready(timeout)  # the first run of a model compiles its plug-ins and interfaces library


# ---------------------------------------------------------------- builds


class Built:
    def __init__(self, out: Path, exe: Path):
        self.out = out
        self.exe = exe
        self.map = out / "service_map.json"


_BUILDS: dict = {}


def build_model(model: Path, out: Path, cflags: str = "", release: bool = False) -> Built:
    from easylab.build import build
    from easylab.pipeline import lower_file

    key = (str(model), cflags, release)
    if key not in _BUILDS:
        program, result = lower_file(str(model))
        assert program is not None, result.report()
        res = build(program, "host", out, extra_cflags=cflags.split(), release=release)
        _BUILDS[key] = Built(out, res.executable)
    return _BUILDS[key]


def build_sim(board: str, model: Path, out: Path, env: dict) -> Built:
    """A simulation build for an MCU board (``easylab build MODEL --board
    BOARD --mcu MCU --sim``: the ATmega2560, the PIC18F4620; once per
    session); `exe` is its simulator harness. A model's `modbus tcp` line is
    left out: the MCU boards have no network (the tests of TCP are
    host-only); on the PIC18 (one EUSART) the Modbus RTU interface moves to
    uart0 (firmware_builds.board_model)."""
    import subprocess

    from firmware_builds import board_model

    key = (board, str(model))
    if key not in _BUILDS:
        model = board_model(board, model, "modbus-rtu", out / "model")
        text = model.read_text()
        if any(line.lstrip().startswith("modbus tcp") for line in text.splitlines()):
            out.mkdir(parents=True, exist_ok=True)
            model = out / model.name
            model.write_text("".join(line for line in text.splitlines(keepends=True)
                                     if not line.lstrip().startswith("modbus tcp")))
        proc = subprocess.run([sys.executable, "-m", "easylab", "build", str(model), "--board", board, "--mcu",
                               SIM_MCUS[board], "--sim", "-o", str(out / board)], capture_output=True, text=True,
                              env=env, timeout=600, stdin=subprocess.DEVNULL)
        assert proc.returncode == 0, f"{board} build of {model} failed:\n{proc.stdout}{proc.stderr}"
        sim = next(Path(line.split(": ", 1)[1]) for line in proc.stdout.splitlines() if line.startswith("simulator: "))
        _BUILDS[key] = Built(out / board, sim)
    return _BUILDS[key]


def build_avr(model: Path, out: Path, env: dict) -> Built:
    """The ATmega2560 simulation build of ``model`` (build_sim)."""
    return build_sim("avr", model, out, env)


# The AVR's harness is an MCU harness like every other.
AvrFirmware = McuFirmware


def build_interp(model: Path, out: Path) -> Built:
    """Local execution needs no build: `exe` is the model file, and the maps
    are those `easylab run` writes (made here once per session)."""
    import shutil

    from easylab.pipeline import lower_file
    from easylab.interp.interfaces import Library
    from easylab.interp.plugins import PluginCache

    key = ("interp", str(model))
    if key not in _BUILDS:
        program, result = lower_file(str(model))
        assert program is not None, result.report()
        out.mkdir(parents=True, exist_ok=True)
        for name, path in Library(program, PluginCache()).files.items():
            if name.startswith("service_map"):
                shutil.copyfile(path, out / name)
        _BUILDS[key] = Built(out, model)
    return _BUILDS[key]


# ---------------------------------------------------------------- raw Modbus



def mbap(tid: int, unit: int, pdu: bytes) -> bytes:
    return struct.pack(">HHHB", tid, 0, len(pdu) + 1, unit) + pdu


class RawTcp:
    def __init__(self, port: int):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=2)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.tid = 0

    def recv_adu(self) -> tuple[int, int, bytes]:
        head = self._exact(7)
        tid, proto, length, unit = struct.unpack(">HHHB", head)
        assert proto == 0
        return tid, unit, self._exact(length - 1)

    def _exact(self, n: int) -> bytes:
        out = b""
        while len(out) < n:
            chunk = self.sock.recv(n - len(out))
            if not chunk:
                raise ConnectionError("closed")
            out += chunk
        return out

    def ask(self, pdu: bytes, unit: int = 1) -> bytes:
        self.tid = (self.tid + 1) & 0xFFFF
        self.sock.sendall(mbap(self.tid, unit, pdu))
        tid, u, reply = self.recv_adu()
        assert tid == self.tid and u == unit
        return reply

    def close(self) -> None:
        self.sock.close()


def read_regs_pdu(fc: int, address: int, count: int) -> bytes:
    return struct.pack(">BHH", fc, address, count)


def _boards_mark(mcu_reason: str | None):
    import pytest
    mcus = [b if mcu_reason is None else pytest.param(b, marks=pytest.mark.skip(reason=f"host-only: {mcu_reason}"))
            for b in SIM_MCUS]
    return pytest.mark.parametrize("board", ["host", *mcus, "interp"], indirect=True)


def host_only(reason: str):
    """Parametrise a test by board, the MCU boards skipped for `reason`
    (local execution runs it: it is the host's)."""
    return _boards_mark(reason)


# Run a test on every board (the fixtures board, builds, svc_all, firmware):
# the host board, the AVR in simavr, the PIC18 in gpsim, local execution.
on_boards = _boards_mark(None)


def tool_available(name: str) -> bool:
    return shutil.which(name) is not None


def run_runtime_harness(tmp_path: Path, name: str, harness: str, runtime_files: tuple[str, ...],
                        sanitize: str) -> subprocess.CompletedProcess:
    """Build a C test harness (text) with runtime_c/'s ``runtime_files``
    under gcc -Werror and the sanitizers ``sanitize``, run it; its run
    (the harness prints its failures)."""
    runtime = ROOT / "runtime_c"
    src, exe = tmp_path / f"{name}.c", tmp_path / name
    src.write_text(harness)
    cmd = ["gcc", "-std=c99", "-g", "-Wall", "-Wextra", "-Werror", f"-fsanitize={sanitize}",
           "-fno-sanitize-recover=all", f"-I{runtime}", str(src), *[str(runtime / f) for f in runtime_files],
           "-o", str(exe)]
    built = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert built.returncode == 0, built.stderr
    return subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)

