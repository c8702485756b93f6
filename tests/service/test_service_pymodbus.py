"""Conformance with a third-party client: pymodbus 3.16's client used
directly, over Modbus TCP and over RTU on the host board's pty, against
tests/service/data/service_all.elab (every item kind; built with ASan and
UBSan). Addresses are the generated map's (service_map.json)."""

from __future__ import annotations

import json
import logging
import math
import struct
import time

import pytest

from svc_testlib import RawPty, host_only, on_boards, rtu_frame

pymodbus = pytest.importorskip("pymodbus")
from pymodbus.client import ModbusSerialClient, ModbusTcpClient  # noqa: E402

logging.getLogger("pymodbus").setLevel(logging.CRITICAL + 1)

UNIT = 3  # service_all.elab: modbus rtu ... unit 3


def f32_regs(x: float) -> list[int]:
    raw = struct.unpack(">I", struct.pack(">f", x))[0]
    return [raw >> 16, raw & 0xFFFF]


def u32_regs(x: int) -> list[int]:
    x &= 0xFFFFFFFF
    return [x >> 16, x & 0xFFFF]


def regs_f32(r: list[int]) -> float:
    return struct.unpack(">f", struct.pack(">HH", *r))[0]


def regs_i32(r: list[int]) -> int:
    v = (r[0] << 16) | r[1]
    return v - (1 << 32) if v & 0x80000000 else v


def s16(v: int) -> int:
    return v - 0x10000 if v & 0x8000 else v


@pytest.fixture(params=["tcp", "rtu"])
def client(request, svc_all, firmware):
    fw = firmware(svc_all.exe)
    if request.param == "tcp":
        c = ModbusTcpClient("127.0.0.1", port=fw.port, timeout=2, retries=0)
    else:
        c = ModbusSerialClient(str(fw.rtu), baudrate=115200, parity="N", timeout=2, retries=0)
    assert c.connect()
    c.fw = fw
    c.kind = request.param
    yield c
    c.close()


def ok(r):
    assert not r.isError(), r
    return r


def exc(r) -> int:
    assert r.isError(), r
    return r.exception_code


@on_boards
def test_the_map_is_what_the_tests_assume(svc_all):
    m = json.loads(svc_all.map.read_text())
    where = {i["name"]: (i["table"], i["address"], i["registers"]) for i in m["items"]}
    assert where["p_flag"] == ("coil", 0, 1) and where["cmd"] == ("coil", 1, 1)
    assert where["p_i32"] == ("holding", 4, 2) and where["p_time"] == ("holding", 10, 2)
    assert where["p_far"] == ("holding", 100, 1)
    assert where["m_f32"] == ("input", 6, 2) and where["m_cmd"] == ("discrete", 1, 1)
    assert m["word_order"] == "big"


@on_boards
def test_reads_every_table(client):
    h = ok(client.read_holding_registers(0, count=12, device_id=UNIT)).registers
    assert [s16(h[0]), h[1], s16(h[2]), h[3]] == [-5, 7, -300, 40000]
    assert regs_i32(h[4:6]) == -100000
    assert (h[6] << 16 | h[7]) == 3000000000
    assert regs_f32(h[8:10]) == 1.5
    assert (h[10] << 16 | h[11]) == 2000  # time: milliseconds
    assert ok(client.read_holding_registers(100, count=1, device_id=UNIT)).registers == [7]
    assert ok(client.read_coils(0, count=2, device_id=UNIT)).bits[:2] == [False, False]
    time.sleep(0.05)  # the mirrors are published one task period after boot
    i = ok(client.read_input_registers(0, count=10, device_id=UNIT)).registers
    assert [s16(i[0]), s16(i[1]), regs_i32(i[2:4]), i[4] << 16 | i[5], regs_f32(i[6:8]), i[8] << 16 | i[9]] == \
        [-5, -300, -100000, 3000000000, 1.5, 2000]
    assert ok(client.read_discrete_inputs(0, count=2, device_id=UNIT)).bits[:2] == [False, False]


@on_boards
def test_writes_every_kind_and_tasks_see_them_at_their_next_release(client):
    ok(client.write_coil(0, True, device_id=UNIT))                        # 05: bool param
    ok(client.write_coil(1, True, device_id=UNIT))                        # 05: bool var
    ok(client.write_register(0, (-77) & 0xFFFF, device_id=UNIT))          # 06: int8
    ok(client.write_register(1, 200, device_id=UNIT))                     # 06: uint8
    ok(client.write_register(2, (-1000) & 0xFFFF, device_id=UNIT))        # 06: int16
    ok(client.write_register(3, 65535, device_id=UNIT))                   # 06: uint16
    ok(client.write_registers(4, u32_regs(-2000000), device_id=UNIT))     # 16: int32
    ok(client.write_registers(6, u32_regs(4294967295), device_id=UNIT))   # 16: uint32
    ok(client.write_registers(8, f32_regs(-9.75), device_id=UNIT))        # 16: float32
    ok(client.write_registers(10, u32_regs(60000), device_id=UNIT))       # 16: time
    ok(client.write_register(100, 4242, device_id=UNIT))                  # 06: explicit address
    h = ok(client.read_holding_registers(0, count=12, device_id=UNIT)).registers
    assert [s16(h[0]), h[1], s16(h[2]), h[3]] == [-77, 200, -1000, 65535]
    assert regs_i32(h[4:6]) == -2000000 and (h[6] << 16 | h[7]) == 4294967295
    assert regs_f32(h[8:10]) == -9.75 and (h[10] << 16 | h[11]) == 60000
    assert ok(client.read_holding_registers(100, count=1, device_id=UNIT)).registers == [4242]
    # The Mirror task (10 ms) latches the params at its next release and
    # publishes at its deadline.
    time.sleep(0.06)
    i = ok(client.read_input_registers(0, count=10, device_id=UNIT)).registers
    assert [s16(i[0]), s16(i[1]), regs_i32(i[2:4]), i[4] << 16 | i[5], regs_f32(i[6:8]), i[8] << 16 | i[9]] == \
        [-77, -1000, -2000000, 4294967295, -9.75, 60000]
    assert ok(client.read_discrete_inputs(0, count=2, device_id=UNIT)).bits[:2] == [True, True]


@on_boards
def test_write_multiple_coils_and_registers(client):
    ok(client.write_coils(0, [True, False], device_id=UNIT))              # 15
    assert ok(client.read_coils(0, count=2, device_id=UNIT)).bits[:2] == [True, False]
    regs = [3, 4, 5, 6] + u32_regs(-1) + u32_regs(7) + f32_regs(0.25) + u32_regs(100)
    ok(client.write_registers(0, regs, device_id=UNIT))                   # 16 over every holding item
    assert ok(client.read_holding_registers(0, count=12, device_id=UNIT)).registers == regs


@on_boards
def test_exceptions(client):
    u = UNIT
    # 01: a function code the slave does not implement.
    assert exc(client.read_exception_status(device_id=u)) == 1
    # 02: one past the end of each table, a hole, half of a 32-bit item.
    assert exc(client.read_holding_registers(101, count=1, device_id=u)) == 2
    assert exc(client.read_holding_registers(0, count=13, device_id=u)) == 2   # 12 is a hole
    assert exc(client.read_holding_registers(99, count=2, device_id=u)) == 2
    assert exc(client.read_input_registers(10, count=1, device_id=u)) == 2
    assert exc(client.read_coils(2, count=1, device_id=u)) == 2
    assert exc(client.read_discrete_inputs(0, count=3, device_id=u)) == 2
    assert exc(client.write_coil(2, True, device_id=u)) == 2
    assert exc(client.write_register(4, 1, device_id=u)) == 2                  # half of p_i32
    assert exc(client.write_registers(5, [1, 2], device_id=u)) == 2           # cuts p_i32 and p_u32
    assert exc(client.write_registers(11, [1], device_id=u)) == 2             # half of p_time
    # 03: values outside the range or the type; nothing changes.
    before = ok(client.read_holding_registers(0, count=12, device_id=u)).registers
    assert exc(client.write_register(0, 101, device_id=u)) == 3               # int8 range -100..100
    assert exc(client.write_register(0, 300, device_id=u)) == 3               # not an int8 at all
    assert exc(client.write_register(1, 201, device_id=u)) == 3               # uint8 range 0..200
    assert exc(client.write_registers(4, u32_regs(2000001), device_id=u)) == 3
    assert exc(client.write_registers(8, f32_regs(100.5), device_id=u)) == 3
    assert exc(client.write_registers(8, f32_regs(math.nan), device_id=u)) == 3
    assert exc(client.write_registers(8, f32_regs(math.inf), device_id=u)) == 3
    assert exc(client.write_registers(10, u32_regs(99), device_id=u)) == 3    # time range 100 ms..60 s
    # All or nothing: the first value is fine, the second is not.
    assert exc(client.write_registers(0, [10, 250], device_id=u)) == 3
    assert ok(client.read_holding_registers(0, count=12, device_id=u)).registers == before


@on_boards
def test_device_identification(client, svc_all):
    m = json.loads(svc_all.map.read_text())
    r = ok(client.read_device_information(read_code=1, device_id=UNIT))
    assert r.information == {0: b"EasyLab", 1: b"service_all", 2: m["easylab"].encode()}
    r = ok(client.read_device_information(read_code=3, device_id=UNIT))
    assert r.information[0x80] == m["program_id"].encode()
    assert r.information[4] == b"Every kind of service item" and r.information[5] == b"service_all"
    r = ok(client.read_device_information(read_code=4, object_id=0x80, device_id=UNIT))
    assert r.information == {0x80: m["program_id"].encode()}


@host_only("Modbus TCP needs a network; the MCU boards have none")
def test_tcp_answers_any_unit_id(svc_all, firmware):
    fw = firmware(svc_all.exe, rtu=False)
    c = ModbusTcpClient("127.0.0.1", port=fw.port, timeout=2, retries=0)
    assert c.connect()
    try:
        for unit in (0, 1, 3, 255):
            assert ok(c.read_holding_registers(100, count=1, device_id=unit)).registers == [7]
    finally:
        c.close()


@on_boards
def test_rtu_broadcast_is_executed_without_a_reply(svc_all, firmware):
    fw = firmware(svc_all.exe, tcp=False)
    # pymodbus itself: a broadcast write expects no reply.
    c = ModbusSerialClient(str(fw.rtu), baudrate=115200, parity="N", timeout=1, retries=0)
    assert c.connect()
    c.write_register(100, 555, device_id=0, no_response_expected=True)
    time.sleep(0.05)
    assert ok(c.read_holding_registers(100, count=1, device_id=UNIT)).registers == [555]
    c.close()
    # On the wire: nothing comes back, not even for an invalid broadcast.
    pty = RawPty(fw.rtu)
    try:
        pty.send(rtu_frame(0, struct.pack(">BHH", 0x06, 100, 777)))
        assert pty.recv(timeout=0.3) == b""
        pty.send(rtu_frame(0, struct.pack(">BHH", 0x06, 0, 999)))     # out of range: no exception either
        assert pty.recv(timeout=0.3) == b""
        pty.send(rtu_frame(0, struct.pack(">BHH", 0x03, 100, 1)))     # a read is not executed
        assert pty.recv(timeout=0.3) == b""
        assert pty.ask(UNIT, struct.pack(">BHH", 0x03, 100, 1)) == bytes([3, 2]) + struct.pack(">H", 777)
        pty.send(rtu_frame(0, bytes([0x0F, 0, 0, 0, 2, 1, 3])))        # 15: both coils on
        assert pty.recv(timeout=0.3) == b""
        assert pty.ask(UNIT, bytes([0x01, 0, 0, 0, 2])) == bytes([1, 1, 3])
    finally:
        pty.close()
