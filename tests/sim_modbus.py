"""A board simulator with one UART on a pty serving Modbus RTU, and the
persist round trip every board with an EEPROM passes (written over Modbus,
there again at the next run with the same --nvram file)."""

from __future__ import annotations

import os
import select
import subprocess
import termios
import time
import tty
from pathlib import Path

from easylab.host_tools.debug_protocol import crc16  # CRC-16/MODBUS


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


def _rtu(*pdu: int) -> bytes:
    frame = bytes(pdu)
    return frame + crc16(frame).to_bytes(2, "little")


def _replies_to_two_frames_written_together(exe: Path, uart: str, tmp_path: Path, *options: str) -> bytes:
    """pt100_sensor's Modbus RTU slave (unit 17 on `uart`) in real time: two
    requests written to its pty in one write, once the firmware answers."""
    tmp_path.mkdir()
    link = tmp_path / uart
    proc = subprocess.Popen([str(exe), f"--{uart}", f"pty:{link}", "--wait", *options], stderr=subprocess.PIPE,
                            text=True)
    try:
        deadline = time.monotonic() + 20
        while not link.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        fd = os.open(link, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(fd)
        one, two = _rtu(17, 3, 0, 0, 0, 1), _rtu(17, 3, 0, 2, 0, 1)  # holding registers 0 and 2
        got = b""
        while not got and time.monotonic() < deadline:  # the first request may meet a firmware still booting
            termios.tcflush(fd, termios.TCIFLUSH)
            os.write(fd, one)
            got = _read_for(fd, 0.5)
        assert got == _rtu(17, 3, 2, 0x03, 0xE8), got  # cal_gain 1000
        os.write(fd, one + two)
        replies = _read_for(fd, 1.5)
        os.close(fd)
        return replies
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def _read_for(fd: int, seconds: float) -> bytes:
    got, end = b"", time.monotonic() + seconds
    while (left := end - time.monotonic()) > 0:
        if select.select([fd], [], [], left)[0]:
            got += os.read(fd, 256)
    return got


def check_rtu_frames_kept_apart(exe: Path, uart: str, tmp_path: Path) -> None:
    """A pty keeps no pauses: two Modbus RTU requests that reach it together
    (a master's frames while the harness was held up by a busy machine) are
    one long frame to pt100_sensor's slave, which answers nothing; with
    --rtu-frames the harness hands them over as a wire would, a silence
    between them, and both are answered."""
    assert _replies_to_two_frames_written_together(exe, uart, tmp_path / "plain") == b""
    assert _replies_to_two_frames_written_together(exe, uart, tmp_path / "framed", "--rtu-frames") == \
        _rtu(17, 3, 2, 0x03, 0xE8) + _rtu(17, 3, 2, 0x03, 0x20)  # cal_gain 1000, alarm_high 800
