"""A board simulator with one UART on a pty serving Modbus RTU, a raw RTU
client of a pty (RawPty, rtu_frame), the persist round trip every board
with an EEPROM passes (written over Modbus, there again at the next run
with the same --nvram file) and the check of --rtu-frames."""

from __future__ import annotations

import os
import struct
import subprocess
import time
from pathlib import Path


class ModbusOnPty:
    """A simulator run with UART `uart` on a pty, for a Modbus client."""

    def __init__(self, exe: Path, uart: str, link: Path, *args):
        self.link = link
        self.proc = subprocess.Popen([str(exe), f"--{uart}", f"pty:{link}", "--wait", *map(str, args)],
                                     stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 20
        while not link.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert link.exists()

    def client(self):
        """A connected pymodbus RTU client at 19200 baud on the pty."""
        from pymodbus.client import ModbusSerialClient

        client = ModbusSerialClient(port=str(self.link), baudrate=19200, parity="N", timeout=2)
        assert client.connect()
        return client

    def stop(self) -> str:
        """Ends the simulator; its stderr."""
        self.proc.terminate()
        self.proc.wait(timeout=10)
        return self.proc.stderr.read()


def read_holding(client, count: int, timeout: float = 20.0) -> list[int]:
    """Holding registers 0..count-1 of unit 17, retried while the firmware boots."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:  # the first request may meet a firmware still booting
        reply = client.read_holding_registers(0, count=count, device_id=17)
        if not reply.isError():
            return reply.registers
    raise AssertionError("no Modbus reply")


def check_persist_round_trip(exe: Path, uart: str, tmp_path: Path, eeprom_bytes: int) -> None:
    """pt100_sensor's cal_offset (a persist param, register 1) written over
    Modbus RTU on `uart` is in the --nvram file (`eeprom_bytes` long) and is
    read back in the next run; the harness names and removes its link."""
    nv = tmp_path / "eeprom.bin"
    link = tmp_path / uart
    h = ModbusOnPty(exe, uart, link, "--nvram", nv)
    try:
        client = h.client()
        assert read_holding(client, 3) == [1000, 0, 800]  # cal_gain, cal_offset, alarm_high
        assert not client.write_register(1, 25, device_id=17).isError()
        assert read_holding(client, 3) == [1000, 25, 800]
        time.sleep(0.5)  # the EEPROM is written between instants
        client.close()
    finally:
        err = h.stop()
    assert f"{uart} on {link} -> /dev/pts/" in err
    assert not link.exists()  # the harness removes its link
    assert nv.stat().st_size == eeprom_bytes and nv.read_bytes() != b"\xff" * eeprom_bytes
    h = ModbusOnPty(exe, uart, link, "--nvram", nv)
    try:
        client = h.client()
        assert read_holding(client, 3) == [1000, 25, 800]
        client.close()
    finally:
        h.stop()


def crc16(data: bytes) -> int:
    """CRC-16/MODBUS (easylab.core.crc, the project's one Python copy)."""
    from easylab.core.crc import crc16 as crc

    return crc(data)


def rtu_frame(unit: int, pdu: bytes) -> bytes:
    body = bytes([unit]) + pdu
    return body + struct.pack("<H", crc16(body))


class RawPty:
    """The client side of a firmware's RTU pty, raw, without pyserial."""

    def __init__(self, link: Path):
        import termios
        import tty
        self.fd = os.open(str(link), os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.fd)
        termios.tcflush(self.fd, termios.TCIOFLUSH)

    def send(self, data: bytes) -> None:
        os.write(self.fd, data)

    def recv(self, timeout: float = 1.0, quiet: float = 0.05) -> bytes:
        """Bytes until `quiet` seconds pass without any (or `timeout`)."""
        import select
        out = b""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return out
            r, _, _ = select.select([self.fd], [], [], min(left, quiet) if out else left)
            if not r:
                if out:
                    return out
                continue
            out += os.read(self.fd, 4096)

    def recv_exactly(self, count: int, timeout: float = 1.0) -> bytes:
        """`count` bytes, as soon as they are all in (fewer at `timeout`)."""
        import select
        out = b""
        deadline = time.monotonic() + timeout
        while len(out) < count:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.fd], [], [], left)[0]:
                break
            out += os.read(self.fd, count - len(out))
        return out

    def ask(self, unit: int, pdu: bytes, timeout: float = 1.0) -> bytes | None:
        """Send a request; the reply's PDU (CRC and unit checked), or None."""
        self.send(rtu_frame(unit, pdu))
        reply = self.recv(timeout)
        if not reply:
            return None
        assert crc16(reply) == 0, reply.hex()
        assert reply[0] == unit, reply.hex()
        return reply[1:-2]

    def close(self) -> None:
        os.close(self.fd)


READ_REG0, READ_REG2 = bytes([3, 0, 0, 0, 1]), bytes([3, 0, 2, 0, 1])  # one holding register: 0, 2


class _Pt100OnPty:
    """pt100_sensor's Modbus RTU slave (unit 17 on `uart`) in real time on a
    raw pty, once the firmware answers."""

    def __init__(self, exe: Path, uart: str, tmp_path: Path, *options: str):
        tmp_path.mkdir()
        link = tmp_path / uart
        self.proc = subprocess.Popen([str(exe), f"--{uart}", f"pty:{link}", "--wait", *options],
                                     stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 20
        while not link.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        self.pty = RawPty(link)
        reply = None
        while reply is None and time.monotonic() < deadline:  # the first request may meet a booting firmware
            reply = self.pty.ask(17, READ_REG0, timeout=0.5)
        assert reply == bytes([3, 2, 0x03, 0xE8]), reply  # cal_gain 1000

    def __enter__(self) -> RawPty:
        return self.pty

    def __exit__(self, *exc) -> None:
        self.pty.close()
        self.proc.terminate()
        self.proc.wait(timeout=10)


def _replies_to_two_frames_written_together(exe: Path, uart: str, tmp_path: Path, *options: str) -> bytes:
    """Two requests written to pt100_sensor's pty in one write."""
    with _Pt100OnPty(exe, uart, tmp_path, *options) as pty:
        pty.send(rtu_frame(17, READ_REG0) + rtu_frame(17, READ_REG2))
        return pty.recv(timeout=1.5, quiet=1.5)


# The link of the checks above (pt100_sensor's Modbus RTU UART).
BAUD = 19200


def _fastest_answer_s(exe: Path, uart: str, tmp_path: Path, asks: int = 12) -> float:
    """The shortest of `asks` round trips of one request, each sent 30 ms
    after the last answer (the shortest: a busy machine only delays)."""
    with _Pt100OnPty(exe, uart, tmp_path, "--rtu-frames") as pty:
        best = float("inf")
        for _ in range(asks):
            time.sleep(0.03)
            start = time.monotonic()
            pty.send(rtu_frame(17, READ_REG0))
            reply = pty.recv_exactly(7, timeout=1.0)
            best = min(best, time.monotonic() - start)
            assert crc16(reply) == 0 and reply[:2] == bytes([17, 3]), reply.hex()
        return best


def check_rtu_frames_kept_apart(exe: Path, uart: str, tmp_path: Path) -> None:
    """A pty keeps no pauses: two Modbus RTU requests that reach it together
    (a master's frames while the harness was held up by a busy machine) are
    one long frame to pt100_sensor's slave, which answers nothing; with
    --rtu-frames the harness hands them over as a wire would, a silence
    between them, and both are answered."""
    assert _replies_to_two_frames_written_together(exe, uart, tmp_path / "plain") == b""
    assert _replies_to_two_frames_written_together(exe, uart, tmp_path / "framed", "--rtu-frames") == \
        rtu_frame(17, bytes([3, 2, 0x03, 0xE8])) + rtu_frame(17, bytes([3, 2, 0x03, 0x20]))  # 1000, alarm_high 800
    # A request that comes after a silence longer than the pause goes to the
    # MCU at once: the pause runs from the end of the frame before, not from
    # the request's arrival (which made each of a master's slots wait it
    # twice, once on the master and once here).
    char_s = 11 / BAUD
    wire_s = (8 + 7) * char_s + 3.5 * char_s  # request, the slave's t3.5, the answer
    fastest = _fastest_answer_s(exe, uart, tmp_path / "after-silence")
    print(f"fastest answer after a silence: {fastest * 1000:.1f} ms, {wire_s * 1000:.1f} ms on the wire")
    assert fastest < wire_s + 0.0035, f"{fastest * 1000:.1f} ms for {wire_s * 1000:.1f} ms on the wire"
