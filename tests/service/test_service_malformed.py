"""Malformed traffic, raw, against the ASan/UBSan build of service_all: bad
CRCs, truncated frames, frames for another unit, oversize requests and
garbage between frames are dropped or answered as the specification says,
and the next valid request still succeeds. TCP: pipelined requests, exact
`length` reads, staying in sync after an exception, broken MBAP headers,
several clients at once (more than the slots: test_service_peers.py)."""

from __future__ import annotations

import random
import socket
import struct
import time

import pytest

from svc_testlib import RawPty, RawTcp, host_only, mbap, on_boards, read_regs_pdu, rtu_frame

UNIT = 3
GAP = 0.03  # longer than the host's RTU silence (5 ms)
P_FAR = read_regs_pdu(0x03, 100, 1)  # holding 100 = p_far, 7 at boot
P_FAR_REPLY = bytes([0x03, 0x02, 0x00, 0x07])


@pytest.fixture
def pty(svc_all, firmware):
    fw = firmware(svc_all.exe, tcp=False)
    p = RawPty(fw.rtu)
    yield p
    p.close()


@pytest.fixture
def fw_tcp(svc_all, firmware):
    return firmware(svc_all.exe, rtu=False)


def still_fine(p: RawPty) -> None:
    assert p.ask(UNIT, P_FAR) == P_FAR_REPLY


# ---------------------------------------------------------------- RTU


@on_boards
def test_bad_crc_is_dropped(pty):
    frame = bytearray(rtu_frame(UNIT, P_FAR))
    frame[-1] ^= 0x55
    pty.send(bytes(frame))
    assert pty.recv(timeout=0.2) == b""
    time.sleep(GAP)
    still_fine(pty)


@on_boards
def test_truncated_frame_is_dropped_at_the_silence(pty):
    pty.send(rtu_frame(UNIT, P_FAR)[:5])
    time.sleep(GAP)
    still_fine(pty)
    pty.send(rtu_frame(UNIT, bytes([0x10, 0, 0, 0, 2, 4, 0, 1]))[:9])   # write multiple, cut
    time.sleep(GAP)
    still_fine(pty)


@on_boards
def test_frames_for_another_unit_are_ignored(pty):
    for unit in (1, 4, 247, 248, 255):
        pty.send(rtu_frame(unit, P_FAR))
        assert pty.recv(timeout=0.15) == b""
    still_fine(pty)


@on_boards
def test_oversize_frames_are_dropped(pty):
    # A write of 125 registers: 259 bytes, more than an RTU frame holds.
    data = b"\x00\x01" * 125
    pty.send(rtu_frame(UNIT, struct.pack(">BHHB", 0x10, 0, 125, 250) + data))
    assert pty.recv(timeout=0.2) == b""
    pty.send(bytes(600))
    assert pty.recv(timeout=0.2) == b""
    time.sleep(GAP)
    still_fine(pty)


@on_boards
def test_garbage_between_frames(pty):
    rng = random.Random(6)
    for _ in range(25):
        pty.send(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 300))))
        pty.recv(timeout=0.02)  # random bytes may happen to be a request for us: whatever it answers
        time.sleep(GAP)
        pty.recv(timeout=0.01)
        # On a simulated board the garbage crosses the line at its baud rate,
        # slower than the machine may write it: a request that follows it
        # without a silence is one bad frame with it (the specification's
        # framing), so a request without an answer is asked again, once.
        assert pty.ask(UNIT, P_FAR) == P_FAR_REPLY or pty.ask(UNIT, P_FAR) == P_FAR_REPLY


@host_only("frames back to back, without a t3.5 silence between them, are one (bad) frame on a timed RTU line, "
           "which the MCUs' UARTs are (EL_MB_PORT_TIMED, as the specification frames); the host's pty has no character "
           "timing, so its receiver ends a frame at the length its function code implies (EL_MB_PORT_UNTIMED)")
def test_requests_back_to_back_in_one_write(pty):
    pty.send(rtu_frame(UNIT, P_FAR) + rtu_frame(UNIT, read_regs_pdu(0x03, 0, 1)) + rtu_frame(4, P_FAR))
    reply = pty.recv(timeout=1.0)
    one = rtu_frame(UNIT, P_FAR_REPLY)
    assert reply[:len(one)] == one
    assert reply[len(one):] == rtu_frame(UNIT, bytes([0x03, 0x02, 0xFF, 0xFB]))  # p_i8 = -5


@pytest.mark.parametrize("pdu, answer", [
    (read_regs_pdu(0x03, 0, 0), bytes([0x83, 3])),                          # quantity 0
    (read_regs_pdu(0x03, 0, 126), bytes([0x83, 3])),                        # above 125
    (read_regs_pdu(0x04, 0, 126), bytes([0x84, 3])),
    (read_regs_pdu(0x01, 0, 2001), bytes([0x81, 3])),                       # above 2000
    (read_regs_pdu(0x02, 0, 0), bytes([0x82, 3])),
    (read_regs_pdu(0x03, 0xFFFF, 2), bytes([0x83, 2])),                     # past 65535
    (read_regs_pdu(0x03, 0, 1) + b"\x00", bytes([0x83, 3])),                # a byte too many
    (bytes([0x03, 0, 0]), bytes([0x83, 3])),                                # too short
    (struct.pack(">BHH", 0x05, 0, 0x1234), bytes([0x85, 3])),               # coil value not 0/FF00
    (struct.pack(">BHHB", 0x10, 0, 2, 3) + bytes(3), bytes([0x90, 3])),     # byte count != 2N
    (struct.pack(">BHHB", 0x10, 0, 124, 248) + bytes(248), None),           # > 123: a 257-byte frame, dropped
    (struct.pack(">BHHB", 0x10, 0, 123, 247) + bytes(247), bytes([0x90, 3])),  # 253-byte PDU, byte count odd
    (struct.pack(">BHHB", 0x10, 0, 1, 2) + bytes(3), bytes([0x90, 3])),     # data longer than the byte count
    (struct.pack(">BHHB", 0x0F, 0, 1969, 247) + bytes(247), bytes([0x8F, 3])),
    (struct.pack(">BHHB", 0x0F, 0, 2, 2) + bytes(2), bytes([0x8F, 3])),     # byte count != ceil(N/8)
    (bytes([0x2B, 0x0D, 0, 0]), bytes([0xAB, 1])),                          # MEI type 13: not here
    (bytes([0x2B, 0x0E, 5, 0]), bytes([0xAB, 3])),                          # read device id code 5
    (bytes([0x2B, 0x0E, 4, 3]), bytes([0xAB, 2])),                          # no object 3
    (bytes([0x2B, 0x0E, 1]), bytes([0xAB, 3])),
    (bytes([0x07]), bytes([0x87, 1])),                                      # read exception status
    (bytes([0x41, 1, 2, 3]), bytes([0xC1, 1])),
    (bytes([0x08, 0, 0, 0x12, 0x34]), bytes([0x88, 1])),                    # diagnostics
])
@on_boards
def test_malformed_requests_get_the_specified_exception(pty, pdu, answer):
    got = pty.ask(UNIT, pdu, timeout=0.5)
    assert got == answer
    time.sleep(GAP)
    still_fine(pty)


@on_boards
def test_read_limits_are_served(svc_all, firmware):
    """125 registers and 2000 bits are allowed; the map ends earlier (02)."""
    fw = firmware(svc_all.exe, tcp=False)
    p = RawPty(fw.rtu)
    try:
        assert p.ask(UNIT, read_regs_pdu(0x03, 0, 125)) == bytes([0x83, 2])
        assert p.ask(UNIT, read_regs_pdu(0x01, 0, 2000)) == bytes([0x81, 2])
        assert p.ask(UNIT, read_regs_pdu(0x01, 0, 2)) == bytes([0x01, 1, 0])
    finally:
        p.close()


# ---------------------------------------------------------------- TCP


@host_only("Modbus TCP needs a network; the MCU boards have none")
def test_tcp_pipelined_requests_and_sync_after_exceptions(fw_tcp):
    c = RawTcp(fw_tcp.port)
    try:
        burst = (mbap(1, 1, P_FAR) + mbap(2, 1, read_regs_pdu(0x03, 0, 0))          # 03
                 + mbap(3, 1, read_regs_pdu(0x03, 0, 1) + b"\xAA\xBB")               # length covers 2 extra bytes
                 + mbap(4, 1, bytes([0x41])) + mbap(5, 9, P_FAR))
        c.sock.sendall(burst)
        assert c.recv_adu() == (1, 1, P_FAR_REPLY)
        assert c.recv_adu() == (2, 1, bytes([0x83, 3]))
        assert c.recv_adu() == (3, 1, bytes([0x83, 3]))
        assert c.recv_adu() == (4, 1, bytes([0xC1, 1]))
        assert c.recv_adu() == (5, 9, P_FAR_REPLY)
        # A request in pieces.
        adu = mbap(6, 1, P_FAR)
        c.sock.sendall(adu[:3])
        time.sleep(0.05)
        c.sock.sendall(adu[3:9])
        time.sleep(0.05)
        c.sock.sendall(adu[9:])
        assert c.recv_adu() == (6, 1, P_FAR_REPLY)
        # The largest PDU (253 bytes) is read whole and answered.
        c.sock.sendall(mbap(7, 1, struct.pack(">BHHB", 0x10, 0, 123, 247) + bytes(247)))
        assert c.recv_adu() == (7, 1, bytes([0x90, 3]))
        assert c.ask(P_FAR) == P_FAR_REPLY
    finally:
        c.close()


@pytest.mark.parametrize("head", [
    struct.pack(">HHHB", 1, 1, 6, 1),       # protocol id 1
    struct.pack(">HHHB", 1, 0, 0, 1),       # length 0
    struct.pack(">HHHB", 1, 0, 1, 1),       # no PDU
    struct.pack(">HHHB", 1, 0, 256, 1),     # longer than any ADU
])
@host_only("Modbus TCP needs a network; the MCU boards have none")
def test_tcp_broken_headers_close_the_connection(fw_tcp, head):
    c = RawTcp(fw_tcp.port)
    c.sock.sendall(head + P_FAR)
    c.sock.settimeout(2)
    try:
        assert c.sock.recv(100) == b""     # closed: the stream cannot be resynchronised
    except ConnectionResetError:
        pass
    c.close()
    c = RawTcp(fw_tcp.port)
    assert c.ask(P_FAR) == P_FAR_REPLY
    c.close()


@host_only("Modbus TCP needs a network; the MCU boards have none")
def test_tcp_several_clients_at_once(fw_tcp):
    clients = [RawTcp(fw_tcp.port) for _ in range(8)]
    try:
        for round_ in range(20):
            for k, c in enumerate(clients):
                c.tid = round_ * 8 + k
                c.sock.sendall(mbap(c.tid, k, P_FAR))
            for k, c in enumerate(clients):
                assert c.recv_adu() == (c.tid, k, P_FAR_REPLY)
    finally:
        for c in clients:
            c.close()


@host_only("Modbus TCP needs a network; the MCU boards have none")
def test_tcp_garbage_then_a_new_connection(fw_tcp):
    rng = random.Random(7)
    for _ in range(20):
        s = socket.create_connection(("127.0.0.1", fw_tcp.port), timeout=2)
        s.sendall(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 600))))
        s.close()
    c = RawTcp(fw_tcp.port)
    assert c.ask(P_FAR) == P_FAR_REPLY
    c.close()
