"""How `easylab remote` keeps real time (generator/remote/realtime.py):
`--realtime`'s SCHED_FIFO and locked memory where the system allows them,
a clear word where it does not, and a warning for links whose bytes pass a
kernel worker thread; `--wait`: polling the link at short deadlines, on a
real pty and a real TCP connection."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
import tty

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import realtime_peers
from easylab.host_tools.transport import FrameTransport, TransportError, TransportTimeout
from easylab.remote.realtime import POLL_DEADLINES_UP_TO_US, polls_its_link

PROBE = ("import os, json; from easylab.remote.realtime import go_real_time; "
         "said = go_real_time({target!r}); print(json.dumps([said, os.sched_getscheduler(0)]))")


def probe(target: str) -> tuple[list[str], int]:
    import json

    proc = subprocess.run([sys.executable, "-c", PROBE.format(target=target)], capture_output=True, text=True,
                          timeout=60, check=True)
    said, policy = json.loads(proc.stdout)
    return said, policy


def test_a_tcp_link_goes_real_time_where_allowed_or_says_why_not():
    said, policy = probe("socket://127.0.0.1:5000")
    if realtime_peers.real_time_prefix():  # this system allows SCHED_FIFO
        assert policy == os.SCHED_FIFO
        assert not [s for s in said if "scheduling" in s], said
    else:
        assert policy == os.SCHED_OTHER
        assert any("real-time scheduling is not allowed here" in s for s in said), said


def test_a_pty_or_serial_link_is_warned_about():
    said, _ = probe("/dev/ttyUSB0")
    assert any("a TCP link (socket://HOST:PORT) does not have that step" in s for s in said), said


@pytest.mark.parametrize("wait,realtime,deadline_us,polls", [
    ("auto", False, 1000, True), ("auto", False, POLL_DEADLINES_UP_TO_US, True),
    ("auto", False, POLL_DEADLINES_UP_TO_US + 1, False), ("auto", False, None, False),
    ("auto", True, 1000, False),  # under SCHED_FIFO a wake-up preempts; polling would starve the CPU
    ("poll", False, 100_000, True), ("poll", True, 1000, True), ("sleep", False, 1000, False)])
def test_when_a_real_time_run_polls_its_link(wait, realtime, deadline_us, polls):
    assert polls_its_link(wait, realtime, deadline_us) is polls


class _Peer:
    """The far end of a real link the transport opens: a pty's master or
    the accepted side of a TCP connection on 127.0.0.1."""

    def __init__(self, kind: str):
        self.kind = kind
        self.conn: socket.socket | None = None
        if kind == "pty":
            self.master, slave = os.openpty()
            tty.setraw(slave)
            self.url = os.ttyname(slave)
            self.slave = slave
        else:
            self.server = socket.socket()
            self.server.bind(("127.0.0.1", 0))
            self.server.listen(1)
            self.url = f"socket://127.0.0.1:{self.server.getsockname()[1]}"

    def _accepted(self) -> socket.socket:
        if self.conn is None:
            self.conn = self.server.accept()[0]
        return self.conn

    def write(self, data: bytes) -> None:
        if self.kind == "pty":
            os.write(self.master, data)
        else:
            self._accepted().sendall(data)

    def close(self) -> None:
        """The peer goes: the master closed, the connection closed."""
        if self.kind == "pty":
            if self.master >= 0:
                os.close(self.master)
                self.master = -1
        else:
            self._accepted().close()

    def end(self) -> None:
        self.close()
        if self.kind == "pty":
            os.close(self.slave)
        else:
            self.server.close()


@pytest.mark.parametrize("kind", ["pty", "tcp"])
def test_a_polling_link_takes_frames_in_pieces_and_sees_its_peer_go(kind):
    """Polling (FrameTransport.poll): a frame that comes a byte at a time is
    whole, the wait spends the CPU instead of sleeping, nothing coming is a
    timeout, and a peer that goes is a lost connection at once, not a
    timeout."""
    peer = _Peer(kind)
    transport = FrameTransport.open(peer.url, 1_000_000)
    try:
        transport.poll(True)
        sender = threading.Thread(target=lambda: [(peer.write(bytes([b])), time.sleep(0.002)) for b in b"frame\x00"])
        cpu, wall = time.process_time(), time.monotonic()
        sender.start()
        assert transport.recv(5.0) == b"frame"
        sender.join()
        with pytest.raises(TransportTimeout):
            transport.recv(0.3)
        cpu, wall = time.process_time() - cpu, time.monotonic() - wall
        assert cpu > 0.6 * wall, (cpu, wall)  # it polled: a sleeping wait costs next to no CPU
        peer.close()
        started = time.monotonic()
        with pytest.raises(TransportError) as lost:
            transport.recv(5.0)
        assert not isinstance(lost.value, TransportTimeout) and time.monotonic() - started < 1.0, lost.value
    finally:
        transport.close()
        peer.end()


@pytest.mark.parametrize("kind", ["pty", "tcp"])
def test_a_sleeping_link_costs_no_cpu_while_it_waits(kind):
    peer = _Peer(kind)
    transport = FrameTransport.open(peer.url, 1_000_000)
    try:
        cpu, wall = time.process_time(), time.monotonic()
        with pytest.raises(TransportTimeout):
            transport.recv(0.3)
        assert time.process_time() - cpu < 0.3 * (time.monotonic() - wall)
        transport.poll(True)
        transport.poll(False)  # back to sleeping
        cpu = time.process_time()
        with pytest.raises(TransportTimeout):
            transport.recv(0.3)
        assert time.process_time() - cpu < 0.1
    finally:
        transport.close()
        peer.end()


@settings(max_examples=30, deadline=None)
@given(frames=st.lists(st.binary(max_size=40).map(lambda b: b.replace(b"\x00", b"\x01")), min_size=1, max_size=8),
       cuts=st.lists(st.integers(min_value=1, max_value=30), max_size=20))
def test_a_polling_link_returns_any_frames_however_the_bytes_are_cut(frames, cuts):
    """Random frames (0x00-delimited) written over a real TCP connection in
    random pieces, with pauses between them: the polling transport returns
    each frame whole and in order."""
    peer = _Peer("tcp")
    transport = FrameTransport.open(peer.url, 1_000_000)
    try:
        transport.poll(True)
        wire = b"".join(f + b"\x00" for f in frames)
        pieces, at = [], 0
        for cut in cuts:
            if at >= len(wire):
                break
            pieces.append(wire[at:at + cut])
            at += cut
        pieces.append(wire[at:])
        sender = threading.Thread(target=lambda: [(peer.write(p), time.sleep(0.0005)) for p in pieces if p])
        sender.start()
        assert [transport.recv(5.0) for _ in frames] == frames
        sender.join()
    finally:
        transport.close()
        peer.end()
