"""`persist` params in non-volatile storage (runtime_c/el_persist.h): kept
across restarts, written only on change, two checksummed copies with a
sequence number so that a torn write leaves the old value; and a power-loss
test: the host firmware is killed (SIGKILL) at 200 random moments while it
persists params under a stream of writes; after every restart each param
holds its old or its new value, never a default or garbage."""

from __future__ import annotations

import random
import struct
import threading
import time

import pytest

from svc_testlib import Firmware, InterpFirmware, RawTcp, crc16

RECORD, SLOT = 10, 20
# service_all.elab's persist params in map order: (name, holding address, type, lo, hi, initial)
PERSIST = [
    ("p_i8", 0, "int8", -100, 100, -5),
    ("p_u8", 1, "uint8", 0, 200, 7),
    ("p_i16", 2, "int16", -1000, 1000, -300),
    ("p_u16", 3, "uint16", 0, 65535, 40000),
    ("p_i32", 4, "int32", -2000000, 2000000, -100000),
    ("p_u32", 6, "uint32", 0, 2 ** 32 - 1, 3000000000),
    ("p_f32", 8, "float32", -10.0, 100.0, 1.5),
    ("p_time", 10, "time", 100, 60000, 2000),
]
BY_NAME = {p[0]: p for p in PERSIST}


def regs_of(kind: str, value) -> list[int]:
    if kind == "float32":
        raw = struct.unpack(">I", struct.pack(">f", value))[0]
    else:
        raw = value & 0xFFFFFFFF
    if kind in ("int8", "uint8", "int16", "uint16"):
        return [raw & 0xFFFF]
    return [raw >> 16, raw & 0xFFFF]


def value_of(kind: str, regs: list[int]):
    if kind == "float32":
        return struct.unpack(">f", struct.pack(">HH", *regs))[0]
    if len(regs) == 2:
        raw = regs[0] << 16 | regs[1]
        return raw - (1 << 32) if kind == "int32" and raw & 0x80000000 else raw
    return regs[0] - 0x10000 if kind in ("int8", "int16") and regs[0] & 0x8000 else regs[0]


def write_pdu(address: int, regs: list[int]) -> bytes:
    if len(regs) == 1:
        return struct.pack(">BHH", 0x06, address, regs[0])
    return struct.pack(">BHHB", 0x10, address, len(regs), 2 * len(regs)) + struct.pack(f">{len(regs)}H", *regs)


def read_all(c: RawTcp) -> dict:
    reply = c.ask(struct.pack(">BHH", 0x03, 0, 12))
    assert reply[:2] == bytes([0x03, 24]), reply.hex()
    regs = list(struct.unpack(">12H", reply[2:]))
    out = {}
    for name, addr, kind, *_ in PERSIST:
        n = 1 if kind in ("int8", "uint8", "int16", "uint16") else 2
        out[name] = value_of(kind, regs[addr:addr + n])
    return out


def random_value(rng: random.Random, kind: str, lo, hi):
    if kind == "float32":
        return struct.unpack(">f", struct.pack(">f", rng.uniform(lo, hi)))[0]
    return rng.randint(lo, hi)


def decode_records(image: bytes, slot: int) -> list[tuple[int, int, int] | None]:
    """(seq, key, value) of copy A and B of a slot, None where the CRC fails."""
    out = []
    for copy in range(2):
        rec = image[slot * SLOT + copy * RECORD: slot * SLOT + (copy + 1) * RECORD]
        if crc16(rec[:8]) != struct.unpack("<H", rec[8:])[0]:
            out.append(None)
        else:
            out.append(struct.unpack("<HHI", rec[:8]))
    return out


@pytest.fixture(scope="module")
def plain(builds):
    """service_all without sanitizers: fast restarts."""
    return builds("service_all")


def start(exe, tmp_path, nvram, board: str = "host") -> tuple[Firmware, RawTcp]:
    fw = (InterpFirmware if board == "interp" else Firmware)(exe, tmp_path, rtu=False, nvram=nvram).start()
    return fw, RawTcp(fw.port)


@pytest.mark.parametrize("board", ["host", "interp"], indirect=True)
def test_persisted_params_survive_a_restart(svc_all, tmp_path, board):
    """On the host board and in local execution (`easylab run --nvram`)."""
    nv = tmp_path / "nv.bin"
    fw, c = start(svc_all.exe, tmp_path, nv, board)
    try:
        assert read_all(c) == {p[0]: p[5] for p in PERSIST}            # erased storage: initial values
        assert not nv.exists()                                          # nothing written before a change
        new = {"p_i8": 99, "p_u8": 0, "p_i16": -1000, "p_u16": 1, "p_i32": 2000000, "p_u32": 4294967295,
               "p_f32": -10.0, "p_time": 60000}
        for name, value in new.items():
            _, addr, kind, *_ = BY_NAME[name]
            assert c.ask(write_pdu(addr, regs_of(kind, value)))[0] in (0x06, 0x10)
        assert c.ask(struct.pack(">BHH", 0x06, 100, 1234))[0] == 0x06     # p_far: not persisted
    finally:
        c.close()
        fw.stop()
    fw, c = start(svc_all.exe, tmp_path, nv, board)
    try:
        assert read_all(c) == new
        assert c.ask(struct.pack(">BHH", 0x03, 100, 1)) == bytes([0x03, 2, 0, 7])
        # Unchanged values are not written again.
        image = nv.read_bytes()
        for name, value in new.items():
            _, addr, kind, *_ = BY_NAME[name]
            c.ask(write_pdu(addr, regs_of(kind, value)))
        assert nv.read_bytes() == image
        _, addr, kind, *_ = BY_NAME["p_i16"]
        c.ask(write_pdu(addr, regs_of(kind, 5)))
        assert nv.read_bytes() != image
    finally:
        c.close()
        fw.stop()


def test_a_torn_copy_leaves_the_old_value(svc_all, tmp_path):
    nv = tmp_path / "nv.bin"
    slot = 2  # p_i16
    fw, c = start(svc_all.exe, tmp_path, nv)
    try:
        c.ask(write_pdu(2, regs_of("int16", 111)))
        c.ask(write_pdu(2, regs_of("int16", 222)))
    finally:
        c.close()
        fw.stop()
    image = bytearray(nv.read_bytes())
    a, b = decode_records(bytes(image), slot)
    assert a is not None and b is not None
    newest = 0 if (a[0] - b[0]) & 0x8000 == 0 and a[0] != b[0] else 1
    assert [a, b][newest][2] & 0xFFFF == 222
    # A write cut short: the newest copy's last bytes never made it.
    torn = bytearray(image)
    at = slot * SLOT + newest * RECORD
    torn[at + 6: at + 10] = b"\xFF\xFF\xFF\xFF"
    nv.write_bytes(bytes(torn))
    fw, c = start(svc_all.exe, tmp_path, nv)
    try:
        assert read_all(c)["p_i16"] == 111
        # The next write goes over the torn copy, never over the good one.
        c.ask(write_pdu(2, regs_of("int16", 333)))
        a2, b2 = decode_records(nv.read_bytes(), slot)
        assert [a2, b2][1 - newest] == [a, b][1 - newest]
        assert [a2, b2][newest][2] & 0xFFFF == 333
    finally:
        c.close()
        fw.stop()
    # Both copies bad, a record of another param, a value out of range: the initial value.
    for damage in ("both", "key", "range"):
        image2 = bytearray(image)
        for copy in range(2):
            at = slot * SLOT + copy * RECORD
            seq, key, value = struct.unpack("<HHI", image2[at:at + 8])
            if damage == "both":
                image2[at] ^= 0xFF
                continue
            if damage == "key":
                key ^= 0x1111
            else:
                value = 5000  # p_i16's range is -1000..1000
            body = struct.pack("<HHI", seq, key, value)
            image2[at:at + RECORD] = body + struct.pack("<H", crc16(body))
        nv.write_bytes(bytes(image2))
        fw, c = start(svc_all.exe, tmp_path, nv)
        try:
            assert read_all(c)["p_i16"] == -300, damage
        finally:
            c.close()
            fw.stop()


def test_power_loss_200_kills(plain, tmp_path):
    """SIGKILL at random moments under a stream of writes of persist params."""
    rng = random.Random(2026)
    nv = tmp_path / "nv.bin"
    allowed = {p[0]: {p[5]} for p in PERSIST}
    kills = 0
    writes_acked = [0]
    t0 = time.monotonic()
    while kills < 200:
        fw = Firmware(plain.exe, tmp_path, rtu=False, nvram=nv).start()
        c = RawTcp(fw.port)
        now = read_all(c)
        for name, value in now.items():
            assert value in allowed[name], (kills, name, value, allowed[name])
        acked = dict(now)
        inflight: list = [None]

        def stream():
            try:
                while True:
                    name, addr, kind, lo, hi, _ = rng.choice(PERSIST)
                    value = random_value(rng, kind, lo, hi)
                    inflight[0] = (name, value)
                    reply = c.ask(write_pdu(addr, regs_of(kind, value)))
                    assert reply[0] in (0x06, 0x10), reply.hex()
                    acked[name] = value
                    inflight[0] = None
                    writes_acked[0] += 1
            except (OSError, ConnectionError, AssertionError):
                return
        worker = threading.Thread(target=stream)
        worker.start()
        time.sleep(rng.uniform(0.0, 0.03))
        fw.kill()
        kills += 1
        worker.join(timeout=10)
        assert not worker.is_alive()
        c.close()
        for name in allowed:
            allowed[name] = {acked[name]}
        if inflight[0] is not None:
            allowed[inflight[0][0]].add(inflight[0][1])
    fw = Firmware(plain.exe, tmp_path, rtu=False, nvram=nv).start()
    c = RawTcp(fw.port)
    try:
        for name, value in read_all(c).items():
            assert value in allowed[name], (name, value, allowed[name])
    finally:
        c.close()
        fw.stop()
    assert writes_acked[0] > 200  # writes really went on while it was killed
    assert time.monotonic() - t0 < 120
