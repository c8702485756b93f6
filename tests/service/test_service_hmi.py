"""The local service API (el_service_get / el_service_set) through the host
board's example HMI (boards/host/host_hmi.c): `get NAME`, `set NAME VALUE`
and `list` lines on a pty, with the same checks as Modbus."""

from __future__ import annotations

import os
import select
import struct
import time

import pytest

from svc_testlib import RawTcp


class Lines:
    def __init__(self, link):
        import termios
        import tty
        self.fd = os.open(str(link), os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.fd)
        termios.tcflush(self.fd, termios.TCIOFLUSH)
        self.buf = b""

    def ask(self, line: str, timeout: float = 2.0) -> str:
        os.write(self.fd, line.encode() + b"\n")
        deadline = time.monotonic() + timeout
        while b"\n" not in self.buf:
            left = deadline - time.monotonic()
            assert left > 0, f"no reply to {line!r}"
            r, _, _ = select.select([self.fd], [], [], left)
            if r:
                self.buf += os.read(self.fd, 4096)
        reply, self.buf = self.buf.split(b"\n", 1)
        return reply.decode()

    def close(self):
        os.close(self.fd)


@pytest.fixture
def hmi(svc_all, firmware):
    fw = firmware(svc_all.exe, hmi=True, rtu=False)
    h = Lines(fw.hmi)
    h.fw = fw
    yield h
    h.close()


def test_get_and_set_every_type(hmi):
    assert hmi.ask("get p_i8") == "ok p_i8 -5"
    assert hmi.ask("get p_u32") == "ok p_u32 3000000000"
    assert hmi.ask("get p_f32") == "ok p_f32 1.5"
    assert hmi.ask("get p_time") == "ok p_time 2000"
    assert hmi.ask("get p_flag") == "ok p_flag 0"
    assert hmi.ask("set p_flag true") == "ok p_flag 1"
    assert hmi.ask("set p_i8 -100") == "ok p_i8 -100"
    assert hmi.ask("set p_u8 200") == "ok p_u8 200"
    assert hmi.ask("set p_i32 -2000000") == "ok p_i32 -2000000"
    assert hmi.ask("set p_u32 4294967295") == "ok p_u32 4294967295"
    assert hmi.ask("set p_f32 99.25") == "ok p_f32 99.25"
    assert hmi.ask("set p_time 100") == "ok p_time 100"
    assert hmi.ask("set cmd 1\r") == "ok cmd 1"
    time.sleep(0.05)  # the Mirror task latches them at its next release
    assert hmi.ask("get m_i32") == "ok m_i32 -2000000"
    assert hmi.ask("get m_f32") == "ok m_f32 99.25"
    assert hmi.ask("get m_cmd") == "ok m_cmd 1"


def test_the_same_checks_as_modbus(hmi):
    assert hmi.ask("set p_i8 101") == "error range p_i8"
    assert hmi.ask("set p_i8 99999999999") == "error range p_i8"
    assert hmi.ask("set p_u8 -1") == "error range p_u8"
    assert hmi.ask("set p_f32 nan") == "error range p_f32"
    assert hmi.ask("set p_f32 1e39") == "error range p_f32"
    assert hmi.ask("set p_time 99") == "error range p_time"
    assert hmi.ask("get p_i8") == "ok p_i8 -5"                     # nothing changed
    assert hmi.ask("set p_i8 five") == "error value p_i8"
    assert hmi.ask("set m_i8 1") == "error read-only m_i8"
    assert hmi.ask("get nothing") == "error unknown nothing"
    assert hmi.ask("get hidden") == "error unknown hidden"          # not a service item
    assert hmi.ask("frobnicate") == "error syntax"
    assert hmi.ask("set p_i8") == "error syntax"
    assert hmi.ask("") == "error syntax"
    assert hmi.ask("get " + "x" * 300) == "error line too long"
    assert hmi.ask("list").split() == ["ok", "p_flag", "p_i8", "p_u8", "p_i16", "p_u16", "p_i32", "p_u32", "p_f32",
                                        "p_time", "p_far", "cmd", "m_flag", "m_i8", "m_i16", "m_i32", "m_u32",
                                        "m_f32", "m_time", "m_cmd"]


def test_hmi_and_modbus_see_one_another(hmi):
    c = RawTcp(hmi.fw.port)
    try:
        assert hmi.ask("set p_far -3") == "ok p_far -3"
        assert c.ask(struct.pack(">BHH", 0x03, 100, 1)) == bytes([0x03, 2, 0xFF, 0xFD])
        assert c.ask(struct.pack(">BHH", 0x06, 100, 12)) == struct.pack(">BHH", 0x06, 100, 12)
        assert hmi.ask("get p_far") == "ok p_far 12"
    finally:
        c.close()
