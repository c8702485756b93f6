"""Helpers of the remote-execution tests: host-board proxies built once per
session, run on a pty, and `easylab remote` against them."""

from __future__ import annotations

import re
import socket
import subprocess
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import pytest

from easylab.pipeline import lower_file
from easylab.remote.proxy import build_proxy
from easylab.remote.stimulus import device_columns as split_devices
from firmware_builds import end_process

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
EASYLAB = [sys.executable, "-m", "easylab"]


def proxy_of(build_cache, model: Path) -> Path:
    """The host-board proxy of ``model`` (built once per session)."""
    def make(out: Path) -> Path:
        program, result = lower_file(model)
        assert program is not None, result.report()
        return build_proxy(program, "host", out).executable
    return build_cache.get(("host-proxy", str(model)), make)


def device_columns(stimulus: Path, model: Path, out: Path) -> Path | None:
    """The device `out` columns of a stimulus (what a host-board proxy
    reads) in ``out``; None when it has none."""
    program, _ = lower_file(model)
    text = split_devices(stimulus.read_text(), program)
    if text is None:
        return None
    out.write_text(text)
    return out


def native_of(build_cache, model: Path) -> Path:
    """The host-board firmware of ``model`` (built once per session)."""
    from firmware_builds import build

    return build_cache.get(("host", str(model)), lambda out: build(model, "host", out)).executable


def run_native(exe: Path, trace: Path, duration: str, stimulus: Path | None) -> None:
    """The host firmware in virtual time: the reference trace."""
    cmd = [str(exe), "--fast", "--duration", duration, "--trace", str(trace)]
    if stimulus is not None:
        cmd += ["--stimulus", str(stimulus)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stderr


def wait_for(path: Path, timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert time.monotonic() < deadline, f"{path} did not appear"
        time.sleep(0.01)


class Proxy:
    """A host-board proxy process with its link on a pty (symlink ``link``),
    or with ``tcp`` on a TCP port of its choosing; ``link`` is then what
    the host opens (``socket://127.0.0.1:PORT``)."""

    def __init__(self, exe: Path, link: Path, *args: str, tcp: bool = False):
        self.link: Path | str = link
        self.proc = subprocess.Popen([str(exe), "--link", "tcp:0" if tcp else f"pty:{link}", *args],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                     stdin=subprocess.DEVNULL)
        if tcp:
            line = self.proc.stderr.readline()  # "PROGRAM: link on 127.0.0.1:PORT"
            found = re.search(r": link on (127\.0\.0\.1:\d+)$", line.rstrip("\n"))
            assert found, f"no port announced: {line!r}"
            self.link = f"socket://{found.group(1)}"
        else:
            wait_for(link)

    def finish(self, timeout: float = 30.0) -> tuple[int, str]:
        try:
            _, err = self.proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
            raise AssertionError(f"the proxy did not end: {err}") from None
        return self.proc.returncode, err

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate()


class SimulatedProxy:
    """A proxy in its board's simulation harness (real time unless
    ``--fast`` is given), its link UART (``--uartN``) on a pty (symlink
    ``link``)."""

    def __init__(self, simulator: Path, uart: int, link: Path, *args: str):
        self.link = link
        self.proc = subprocess.Popen([str(simulator), f"--uart{uart}", f"pty:{link}", *args],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                                     stdin=subprocess.DEVNULL)
        wait_for(link)

    def end(self) -> str:
        """End the simulation (its files are complete then); its stderr."""
        return end_process(self.proc)[1]


def remote(model: Path, target: Path | str, *args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([*EASYLAB, "remote", str(model), "--target", str(target), *args], capture_output=True,
                          text=True, timeout=timeout, stdin=subprocess.DEVNULL)


# A real-time run whose host a loaded machine delays past K deadlines in a
# row ends in the proxy's safe state, as it must (and says so): such a run
# is tried again, at most this many times in all; a wrong trace never is.
REAL_TIME_ATTEMPTS = 3
LATE_HOST = "the proxy applied its safe values"


@dataclass
class RealTimeRun:
    proc: subprocess.CompletedProcess  # easylab remote
    elapsed: float  # its wall-clock seconds
    proxy_stderr: str
    run_dir: Path  # remote.csv, the proxy's own files


def real_time_run(tmp_path: Path, start_proxy, model: Path, *args: str) -> RealTimeRun:
    """`easylab remote MODEL --target LINK --trace run_dir/remote.csv ARGS`
    against ``start_proxy(run_dir)`` (a started SimulatedProxy), tried
    again when the host was late (LATE_HOST), at most REAL_TIME_ATTEMPTS
    times; the test fails when every attempt was."""
    late = []
    for attempt in range(REAL_TIME_ATTEMPTS):
        run_dir = tmp_path / f"run{attempt}"
        run_dir.mkdir()
        proxy = start_proxy(run_dir)
        try:
            started = time.monotonic()
            proc = remote(model, proxy.link, "--trace", str(run_dir / "remote.csv"), *args)
            elapsed = time.monotonic() - started
        finally:
            err = proxy.end()
        if proc.returncode != 0 and LATE_HOST in proc.stderr:
            late.append(proc.stderr.strip())
            continue
        return RealTimeRun(proc, elapsed, err, run_dir)
    pytest.fail(f"the host was late in every one of {REAL_TIME_ATTEMPTS} runs:\n" + "\n".join(late))


def assert_host_trace_is_native(traced: Path, native: Path, proc: subprocess.CompletedProcess, err: str = "") -> int:
    """The host's values of a real-time run are the firmware's, instant by
    instant. A value the proxy received after its deadline (the host is a
    process on a shared machine: 1 ms deadlines are often missed) is an
    overrun: held, counted and traced as a status event with the count so
    far (docs/remote.md). Returns the number of such events."""
    rows = traced.read_bytes().splitlines(keepends=True)
    events = [r for r in rows if r.startswith(b"#status,")]
    assert b"".join(r for r in rows if not r.startswith(b"#status,")) == native.read_bytes(), err
    assert native.read_bytes().count(b"\n") > 20, "the stimulus should make the model move"
    if events:
        counted = re.search(r"the proxy counted (\d+) overruns", proc.stderr)
        assert counted and int(events[-1].split(b",")[3]) <= int(counted.group(1)), proc.stderr
    return len(events)


class LatencyRelay:
    """Injected latency on a real link: a TCP relay between `easylab remote`
    (``url``, ``socket://127.0.0.1:PORT``) and a proxy's TCP link
    (``target``, ``socket://...``) that holds the host's bytes for
    ``stall_s`` once every ``every_s``, as a congested link does: the DOWN
    frames sent meanwhile reach the proxy after their deadlines."""

    def __init__(self, target: str, stall_s: float, every_s: float):
        import socket
        import threading

        host, port = target.removeprefix("socket://").split(":")
        self.upstream = (host, int(port))
        self.stall_s, self.every_s = stall_s, every_s
        self.server = socket.create_server(("127.0.0.1", 0))
        self.url = f"socket://127.0.0.1:{self.server.getsockname()[1]}"
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, name="latency-relay", daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        import select
        import socket

        self.server.settimeout(30)
        host, _ = self.server.accept()
        proxy = socket.create_connection(self.upstream)
        for s in (host, proxy):
            s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        held, start = b"", time.monotonic()
        try:
            while not self._stop.is_set():
                phase = (time.monotonic() - start) % self.every_s
                stalled = self.every_s - self.stall_s <= phase  # the last stall_s of every period
                ready, _, _ = select.select([host, proxy], [], [], 0.001)
                for s in ready:
                    data = s.recv(4096)
                    if not data:
                        return
                    if s is proxy:
                        host.sendall(data)
                    else:
                        held += data
                if held and not stalled:
                    proxy.sendall(held)
                    held = b""
        except OSError:
            return
        finally:
            host.close()
            proxy.close()

    def close(self) -> None:
        self._stop.set()
        self.thread.join(5)
        self.server.close()


def uart_resample(data: bytes, sent_baud: int, read_baud: int) -> bytes:
    """What a UART reading at ``read_baud`` makes of ``data`` sent back to
    back at ``sent_baud`` (8N1, the line idle before and after): it waits
    for a start bit's falling edge, samples each bit in its middle at its
    own rate and keeps the byte, stop bit or not (as a driver that ignores
    the framing error flag). Equal rates give ``data`` back. Times are
    integers in units of 1 / (sent_baud * read_baud) s."""
    ts, tr = read_baud, sent_baud  # one bit on each side
    end = 10 * ts * len(data)

    def level(t: int) -> int:
        if t < 0 or t >= end:
            return 1
        k, bit = divmod(t // ts, 10)
        return 0 if bit == 0 else 1 if bit == 9 else (data[k] >> (bit - 1)) & 1

    out, t = bytearray(), 0
    while True:
        j = -(-t // ts)  # the edges are at the sender's bit boundaries
        while j * ts < end and not (level(j * ts) == 0 and level(j * ts - 1) == 1):
            j += 1
        if j * ts >= end:
            return bytes(out)
        start = j * ts
        out.append(sum(level(start + (2 * i + 3) * tr // 2) << i for i in range(8)))
        t = start + 19 * tr // 2  # the middle of the stop bit: ready for the next start bit


class BaudMismatchRelay:
    """Two ends of a serial link at different baud rates, on real ptys:
    relays between a proxy's pty link (``target``, the proxy at
    ``proxy_baud``) and a new pty (symlink ``link``, for `easylab remote`
    at ``host_baud``), each way through uart_resample with the sender's
    and the reader's rates."""

    def __init__(self, target: Path, link: Path, proxy_baud: int, host_baud: int):
        import os
        import threading
        import tty

        self.proxy_fd = os.open(target, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.proxy_fd)
        self.master, slave = os.openpty()
        tty.setraw(slave)
        self.slave = slave  # kept open: the host's side outlives each of its opens
        link.symlink_to(os.ttyname(slave))
        self.link = link
        self.bauds = (proxy_baud, host_baud)
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, name="baud-relay", daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        import os
        import select

        proxy_baud, host_baud = self.bauds
        while not self._stop.is_set():
            ready, _, _ = select.select([self.proxy_fd, self.master], [], [], 0.01)
            for fd in ready:
                try:
                    data = os.read(fd, 4096)
                except OSError:
                    return
                if fd == self.proxy_fd:
                    os.write(self.master, uart_resample(data, proxy_baud, host_baud))
                else:
                    os.write(self.proxy_fd, uart_resample(data, host_baud, proxy_baud))

    def close(self) -> None:
        import os

        self._stop.set()
        self.thread.join(5)
        for fd in (self.proxy_fd, self.master, self.slave):
            os.close(fd)


def free_port() -> int:
    """A TCP port nobody listens on now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def connect(port: int, proc: subprocess.Popen, timeout: float = 120.0):
    """A debug client, once the host side listens (its first run compiles
    the interfaces library)."""
    from easylab.host_tools.debug_protocol import DebugClient

    deadline = time.monotonic() + timeout
    while True:
        try:
            return DebugClient.open(f"socket://127.0.0.1:{port}", 2.0)
        except Exception:
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "the debug interface did not open"
            time.sleep(0.1)


@dataclass
class DebuggedRun:
    """`easylab remote --fast --debug tcp:PORT,halt` under a test."""

    host: subprocess.Popen
    client: object
    maps: Path
    trace: Path


@contextmanager
def debugged_remote_run(proxy: Proxy, model: Path, tmp_path: Path, *args: str):
    """Run ``model`` in lock-step against ``proxy`` with its debug interface
    on a TCP port, halted at its start, its maps and trace in ``tmp_path``;
    yields a DebuggedRun with a connected client. When the block ends the
    run must have ended (or end) with status 0, and the proxy too;
    whatever happens, nothing is left running."""
    port, maps, trace = free_port(), tmp_path / "maps", tmp_path / "remote.csv"
    host = subprocess.Popen([*EASYLAB, "remote", str(model), "--target", str(proxy.link), "--fast",
                             "--trace", str(trace), "--debug", f"tcp:{port},halt", "--maps", str(maps), *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    client = None
    try:
        client = connect(port, host)
        yield DebuggedRun(host, client, maps, trace)
        _, err = host.communicate(timeout=120)
        assert host.returncode == 0, err
        status, proxy_err = proxy.finish()
        assert status == 0, proxy_err
    finally:
        if client:
            client.close()
        if host.poll() is None:
            host.kill()
            host.communicate()
        proxy.kill()
