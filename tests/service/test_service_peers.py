"""Peers that must not stall a program: a Modbus TCP client that sends
requests and never reads the replies costs the host firmware's 5 ms task no
activation (it is dropped, never waited for), nor does an RTU client on the
pty that never reads (the replies nobody reads are discarded), and idle TCP
clients never lock a new client out (it takes the slot of the least
recently active one)."""

from __future__ import annotations

import socket
import subprocess
import time
from pathlib import Path

import pytest

import realtime_peers
from realtime_peers import flood_without_reading, overruns, real_time_prefix
from svc_testlib import RawPty, RawTcp, free_port, host_only, mbap, read_regs_pdu, rtu_frame

GAIN = read_regs_pdu(0x03, 0, 1)  # holding 0 = gain, 3 at boot (tests/service/data/service_peers.elab)
GAIN_REPLY = bytes([0x03, 0x02, 0x00, 0x03])
# Read Device Identification, extended: about 110 reply bytes for 11 request
# bytes, so a client that does not read fills the socket buffers quickly.
IDENTIFY = bytes([0x2B, 0x0E, 0x03, 0x00])

# Long enough for the flooding client to be dropped several times; the task
# runs 1,600 activations meanwhile, each of which must keep its deadline.
RUN_SECONDS = 8


def start_firmware(exe, port: int, prefix: list[str], rtu: Path | None = None) -> subprocess.Popen:
    """The firmware for RUN_SECONDS, serving TCP on `port` (and RTU on a
    pty whose link is `rtu`), once it accepts connections."""
    args = [*prefix, str(exe), "--duration", f"{RUN_SECONDS}s", "--modbus-tcp", str(port)]
    if rtu is not None:
        args += ["--modbus-rtu", f"pty:{rtu}"]
    proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            stdin=subprocess.DEVNULL)
    deadline = time.monotonic() + 10
    while True:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
            if rtu is None or rtu.exists():
                return proc
        except OSError:
            pass
        assert proc.poll() is None, proc.communicate()[1]
        assert time.monotonic() < deadline, "the firmware did not come up"
        time.sleep(0.01)


def skip_unless_deadlines_hold(exe, prefix: list[str]) -> None:
    """Skip when this machine misses 5 ms deadlines with no client at all."""
    realtime_peers.skip_unless_deadlines_hold(
        prefix, lambda: start_firmware(exe, free_port(), []).communicate(timeout=RUN_SECONDS + 30)[1])


@pytest.mark.realtime
def test_a_client_that_never_reads_costs_a_5ms_task_no_activation(builds):
    """The client floods requests and never reads; each time the firmware
    drops it, it connects again and goes on. Meanwhile a reading client is
    still served, and the 5 ms task overruns not once."""
    exe = builds("service_peers").exe
    prefix = real_time_prefix()
    skip_unless_deadlines_hold(exe, prefix)
    port = free_port()
    proc = start_firmware(exe, port, prefix)
    burst = b"".join(mbap(tid, 1, IDENTIFY) for tid in range(100))

    def served_by_reader() -> bool:
        reader = RawTcp(port)
        try:
            return reader.ask(GAIN) == GAIN_REPLY
        finally:
            reader.close()

    drops, served = flood_without_reading(proc, port, RUN_SECONDS - 2, lambda: burst, served_by_reader)
    _, err = proc.communicate(timeout=RUN_SECONDS + 30)
    assert proc.returncode == 0, err
    assert drops >= 1, "the client that does not read was never dropped"
    assert served
    assert overruns(err) == 0, err


@pytest.mark.realtime
def test_an_rtu_client_that_never_reads_costs_a_5ms_task_no_activation(builds, tmp_path):
    """A client on the RTU pty writes a request every 2 ms and never reads:
    once the pty is full of its replies they are discarded, never waited
    for. The next client is served, and the 5 ms task overruns not once."""
    exe = builds("service_peers").exe
    prefix = real_time_prefix()
    skip_unless_deadlines_hold(exe, prefix)
    link = tmp_path / "rtu"
    proc = start_firmware(exe, free_port(), prefix, rtu=link)
    request = rtu_frame(1, IDENTIFY)
    writer = RawPty(link)
    try:
        end = time.monotonic() + RUN_SECONDS - 2
        while time.monotonic() < end and proc.poll() is None:
            writer.send(request)
            time.sleep(0.002)
    finally:
        writer.close()
    time.sleep(0.5)  # the requests still on their way are answered (into the void) by then
    reader = RawPty(link)
    try:
        assert reader.ask(1, GAIN) == GAIN_REPLY
    finally:
        reader.close()
    _, err = proc.communicate(timeout=RUN_SECONDS + 30)
    assert proc.returncode == 0, err
    assert overruns(err) == 0, err


# ---------------------------------------------------------------- idle clients


def assert_closed(sock: socket.socket) -> None:
    sock.settimeout(2)
    try:
        assert sock.recv(100) == b""
    except ConnectionResetError:
        pass


@host_only("Modbus TCP needs a network; the MCU boards have none")
def test_ten_idle_clients_lock_no_one_out(svc_all, firmware):
    """Ten clients that connect and never send a byte take every slot; a new
    client is served at once, in the slot of the oldest of them."""
    fw = firmware(svc_all.exe, rtu=False)
    idle = [socket.create_connection(("127.0.0.1", fw.port), timeout=2) for _ in range(10)]
    try:
        time.sleep(0.2)  # every one accepted
        for _ in range(3):
            c = RawTcp(fw.port)
            assert c.ask(read_regs_pdu(0x03, 100, 1)) == bytes([0x03, 0x02, 0x00, 0x07])
            c.close()
        assert_closed(idle[0])
    finally:
        for s in idle:
            s.close()


@host_only("Modbus TCP needs a network; the MCU boards have none")
def test_a_new_client_takes_the_slot_of_the_least_recently_active(svc_all, firmware):
    """With every slot taken by clients that asked in turn, an eleventh is
    served and the first (its last request the oldest) is closed; the
    other nine stay served, then the next newcomer closes the client that
    has been quiet longest since."""
    fw = firmware(svc_all.exe, rtu=False)
    p_far = read_regs_pdu(0x03, 100, 1)
    reply = bytes([0x03, 0x02, 0x00, 0x07])
    clients = [RawTcp(fw.port) for _ in range(10)]
    extra = []
    try:
        for c in clients:
            assert c.ask(p_far) == reply
        extra.append(RawTcp(fw.port))
        assert extra[0].ask(p_far) == reply
        assert_closed(clients[0].sock)
        for c in clients[2:]:  # clients[1] stays quiet
            assert c.ask(p_far) == reply
        extra.append(RawTcp(fw.port))
        assert extra[1].ask(p_far) == reply
        assert_closed(clients[1].sock)
        for c in clients[2:] + extra:
            assert c.ask(p_far) == reply
    finally:
        for c in clients + extra:
            c.close()

