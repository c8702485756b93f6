"""A debugger that sends requests and never reads the responses costs the
host firmware's 5 ms task no activation (docs/protocol.md, "A debugger
that does not read"): on the pty, once the kernel and the server's buffer
are full, its responses are dropped and counted (tx_dropped), said once on
stderr; over TCP the client is dropped, said on stderr, and the next client
is served."""

from __future__ import annotations

import os
import re
import subprocess
import time
import tty
from pathlib import Path

import pytest

import realtime_peers
from debug_testlib import built
from easylab.host_tools.debug_protocol import DebugClient, K, encode_frame
from realtime_peers import flood_without_reading, overruns, real_time_prefix

# Long enough to fill the kernel's buffers and then some; the task runs 800
# activations meanwhile, each of which must keep its deadline.
RUN_SECONDS = 4
PTY_DROPPING = "debug interface: the debugger does not read its responses on"
TCP_DROPPED = "debug interface: the client does not read its responses: dropped"


# Requests every 2 ms on the pty: about 60 kB of responses a second, which
# fill the kernel's buffers within about a second. Over TCP, bursts as fast
# as the socket takes them: they fill a socket's buffers however large the
# kernel makes them.
BURST = 4
TCP_BURST = 32


def burst(first_seq: int, n: int = BURST) -> bytes:
    """n GET_COUNTERS requests (about 30 response bytes each)."""
    return b"".join(encode_frame((first_seq + i) & 0xFF, K.CMD_GET_COUNTERS) for i in range(n))


def start_pty(exe: Path, link: Path, prefix: list[str]) -> subprocess.Popen:
    proc = subprocess.Popen([*prefix, str(exe), "--debug", f"pty:{link}", "--duration", f"{RUN_SECONDS}s"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    deadline = time.monotonic() + 10
    while not link.exists():
        assert proc.poll() is None, proc.communicate()[1]
        assert time.monotonic() < deadline, "the debug link did not appear"
        time.sleep(0.01)
    return proc


def start_tcp(exe: Path, prefix: list[str]) -> tuple[subprocess.Popen, int]:
    proc = subprocess.Popen([*prefix, str(exe), "--debug", "tcp:0", "--duration", f"{RUN_SECONDS}s"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    line = proc.stderr.readline()  # "PROG: debug interface on 127.0.0.1:PORT"
    found = re.search(r": debug interface on 127\.0\.0\.1:(\d+)$", line.rstrip("\n"))
    assert found, f"no port announced: {line!r}"
    return proc, int(found.group(1))


def skip_unless_deadlines_hold(exe: Path, prefix: list[str], tmp_path: Path) -> None:
    realtime_peers.skip_unless_deadlines_hold(
        prefix, lambda: start_pty(exe, tmp_path / "baseline", []).communicate(timeout=RUN_SECONDS + 30)[1])


@pytest.mark.realtime
def test_a_debugger_that_never_reads_the_pty_costs_a_5ms_task_no_activation(tmp_path):
    """The debugger sends requests on the pty every 2 ms and never reads: the
    responses fill the pty, then the server's buffer, then are dropped and
    counted, never waited for. The 5 ms task overruns not once, the
    program says so once, and a debugger that reads afterwards is served
    and sees the count."""
    exe = built("debug_peers")
    prefix = real_time_prefix()
    skip_unless_deadlines_hold(exe, prefix, tmp_path)
    link = tmp_path / "debug"
    proc = start_pty(exe, link, prefix)
    fd = os.open(link, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    tty.setraw(fd)
    seq = 0
    try:
        end = time.monotonic() + RUN_SECONDS - 1.5
        while time.monotonic() < end and proc.poll() is None:
            try:
                os.write(fd, burst(seq))
                seq += BURST
            except BlockingIOError:
                pass  # the program has not taken the last requests yet
            time.sleep(0.002)
        reader = DebugClient.open(str(link), 2.0)  # reads what waits, then asks
        try:
            reader.hello()
            dropped = reader.counters()["tx_dropped"]
        finally:
            reader.close()
    finally:
        os.close(fd)
    _, err = proc.communicate(timeout=RUN_SECONDS + 30)
    assert proc.returncode == 0, err
    assert overruns(err) == 0, err
    assert dropped > 0, err
    assert err.count(PTY_DROPPING) == 1, err


@pytest.mark.realtime
def test_a_debugger_that_never_reads_over_tcp_costs_a_5ms_task_no_activation(tmp_path):
    """The client floods requests and never reads; each time the program
    drops it (and says so), it connects again and goes on. A client that
    reads is served meanwhile, and the 5 ms task overruns not once."""
    exe = built("debug_peers")
    prefix = real_time_prefix()
    skip_unless_deadlines_hold(exe, prefix, tmp_path)
    proc, port = start_tcp(exe, prefix)
    sent = [0]

    def next_burst() -> bytes:
        sent[0] += TCP_BURST
        return burst(sent[0] - TCP_BURST, TCP_BURST)

    def served_by_reader() -> bool:
        reader = DebugClient.open(f"socket://127.0.0.1:{port}", 2.0)
        try:
            return reader.hello().version == K.PROTOCOL_VERSION
        finally:
            reader.close()

    drops, served = flood_without_reading(proc, port, RUN_SECONDS - 1.5, next_burst, served_by_reader)
    _, err = proc.communicate(timeout=RUN_SECONDS + 30)
    assert proc.returncode == 0, err
    assert overruns(err) == 0, err
    assert drops >= 1, "the client that does not read was never dropped"
    assert served
    assert err.count(TCP_DROPPED) >= 1, err
