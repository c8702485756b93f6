"""A host that starts a proxy and never reads its frames costs the proxy's
5 ms task no activation (docs/remote.md, "A host that does not read"): it
is a link failure, said once on stderr; over TCP its connection is closed,
on the pty the link is down (its requests ignored) until it reads. Either
way no valid frame comes, and the proxy's watchdog applies the safe values,
which a host that reads afterwards finds counted."""

from __future__ import annotations

import os
import re
import socket
import struct
import subprocess
import time
import tty
from pathlib import Path

import pytest

import realtime_peers
from easylab.remote import protocol as P
from easylab.remote.protocol import K
from realtime_peers import overruns, real_time_prefix
from remote_testlib import proxy_of, wait_for

MODEL = Path(__file__).resolve().parent / "data" / "sense_only.elab"
# Long enough to fill the kernel's buffers and then some; the task runs 800
# activations meanwhile, each of which must keep its deadline.
RUN_SECONDS = 4
FAILURE = "link: the host does not read its frames: link failure"
START = P.encode(K.CMD_START, 0, bytes([K.MODE_REAL_TIME]))
# 8 HELLOs every 2 ms: valid frames, which keep the watchdog quiet as long
# as the proxy takes them; their answers (64 kB a second) and the UP frames
# fill the kernel's buffers within about a second.
HELLOS = b"".join(P.encode(K.CMD_HELLO, 0) for _ in range(8))


def start_proxy(exe: Path, link: str, prefix: list[str]) -> subprocess.Popen:
    return subprocess.Popen([*prefix, str(exe), "--link", link, "--duration", f"{RUN_SECONDS}s"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)


def port_of(proc: subprocess.Popen) -> int:
    line = proc.stderr.readline()  # "PROG: link on 127.0.0.1:PORT"
    found = re.search(r": link on 127\.0\.0\.1:(\d+)$", line.rstrip("\n"))
    assert found, f"no port announced: {line!r}"
    return int(found.group(1))


def skip_unless_deadlines_hold(exe: Path, prefix: list[str]) -> None:
    """Skip when a proxy started by a host that reads nothing and sends
    nothing more (the watchdog applies the safe values) misses 5 ms
    deadlines on this machine."""
    def baseline() -> str:
        proc = start_proxy(exe, "tcp:0", [])
        with socket.create_connection(("127.0.0.1", port_of(proc))) as s:
            s.sendall(START)
            return proc.communicate(timeout=RUN_SECONDS + 30)[1]
    realtime_peers.skip_unless_deadlines_hold(prefix, baseline)


def watchdog_count(read, write) -> int:
    """The proxy's watchdog counter, asked by a host that reads (``read()``:
    bytes received so far, ``write(bytes)``)."""
    write(b"\x00" + P.encode(K.CMD_COUNTERS, 0))  # a delimiter first: whatever part of a frame came before
    pending = b""
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline:
        pending += read()
        *frames, pending = pending.split(b"\x00")
        for wire in frames:
            frame = P.decode(wire)
            if frame is not None and frame[0] == K.CMD_COUNTERS | K.RESPONSE:
                return struct.unpack_from(f"<{K.COUNTER_COUNT}H", frame[2], 1)[K.COUNTER_WATCHDOG]
        time.sleep(0.005)
    raise AssertionError("no COUNTERS answer")


@pytest.mark.realtime
def test_a_host_that_never_reads_the_pty_costs_a_5ms_task_no_activation(build_cache, tmp_path):
    """The host starts the proxy on the pty, then sends HELLOs and never
    reads: once the pty and the link's buffer are full the link has failed
    (said once), the host's requests are ignored, the watchdog applies the
    safe values, and the 5 ms task overruns not once. A host that reads
    everything brings the link back and finds the watchdog counted."""
    exe = proxy_of(build_cache, MODEL)
    prefix = real_time_prefix()
    skip_unless_deadlines_hold(exe, prefix)
    link = tmp_path / "link"
    proc = start_proxy(exe, f"pty:{link}", prefix)
    wait_for(link)
    fd = os.open(link, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    tty.setraw(fd)

    def read() -> bytes:
        try:
            return os.read(fd, 65536)
        except BlockingIOError:
            return b""

    try:
        os.write(fd, START)
        end = time.monotonic() + RUN_SECONDS - 1.5
        while time.monotonic() < end and proc.poll() is None:
            try:
                os.write(fd, HELLOS)
            except BlockingIOError:
                pass  # the proxy has not taken the last ones yet
            time.sleep(0.002)
        drained = time.monotonic() + 0.3
        while time.monotonic() < drained:  # a host that reads: everything that waits
            read()
            time.sleep(0.002)
        watchdog = watchdog_count(read, lambda b: os.write(fd, b))
    finally:
        os.close(fd)
    _, err = proc.communicate(timeout=RUN_SECONDS + 30)
    assert proc.returncode == 0, err
    assert overruns(err) == 0, err
    assert err.count(FAILURE) == 1, err
    assert "link: the host reads its frames again" in err, err
    assert watchdog >= 1, err


def non_reading_host(port: int) -> socket.socket:
    """A host with the smallest receive buffer, which starts the proxy and
    never reads."""
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.connect(("127.0.0.1", port))
    s.sendall(START)
    s.setblocking(False)
    return s


@pytest.mark.realtime
def test_a_host_that_never_reads_over_tcp_costs_a_5ms_task_no_activation(build_cache, tmp_path):
    """The host starts the proxy over TCP, then sends HELLOs and never
    reads: its connection is closed (a link failure, said on stderr), and
    the 5 ms task overruns not once. A host that reads, connecting next,
    finds the watchdog counted."""
    exe = proxy_of(build_cache, MODEL)
    prefix = real_time_prefix()
    skip_unless_deadlines_hold(exe, prefix)
    proc = start_proxy(exe, "tcp:0", prefix)
    port = port_of(proc)
    host = non_reading_host(port)
    closed = False
    try:
        end = time.monotonic() + RUN_SECONDS - 1.5
        while time.monotonic() < end and proc.poll() is None and not closed:
            try:
                host.send(HELLOS)
            except BlockingIOError:
                pass  # both socket buffers full: the proxy has stopped taking requests
            except (ConnectionResetError, BrokenPipeError):
                closed = True
            time.sleep(0.002)
    finally:
        host.close()
    with socket.create_connection(("127.0.0.1", port), timeout=2) as reader:
        reader.setblocking(False)

        def read() -> bytes:
            try:
                return reader.recv(65536)
            except BlockingIOError:
                return b""

        time.sleep(0.3)  # the watchdog's time without a valid frame
        watchdog = watchdog_count(read, reader.sendall)
    _, err = proc.communicate(timeout=RUN_SECONDS + 30)
    assert proc.returncode == 0, err
    assert overruns(err) == 0, err
    assert closed, "the host that does not read was never disconnected"
    assert err.count(FAILURE) == 1, err
    assert watchdog >= 1, err
