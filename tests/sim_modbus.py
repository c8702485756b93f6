"""A board simulator with one UART on a pty serving Modbus RTU, and the
persist round trip every board with an EEPROM passes (written over Modbus,
there again at the next run with the same --nvram file)."""

from __future__ import annotations

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
