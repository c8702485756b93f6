"""A Modbus link to an EasyLab slave over TCP or RTU (pymodbus client), with
one-line errors: :class:`LinkError` for a link that cannot be opened or a
device that does not answer, :class:`DeviceException` for a Modbus
exception reply. No pymodbus traceback or log line reaches the user.
"""

from __future__ import annotations

import logging
from dataclasses import asdict, dataclass

EXCEPTIONS = {1: "illegal function", 2: "illegal data address", 3: "illegal data value",
              4: "server device failure", 5: "acknowledge", 6: "server device busy"}
PARITIES = {"N": "N", "E": "E", "O": "O", "NONE": "N", "EVEN": "E", "ODD": "O"}

# Device identification objects (43/14) of an EasyLab slave.
ID_VENDOR, ID_PRODUCT_CODE, ID_REVISION, ID_PRODUCT_NAME, ID_MODEL_NAME, ID_PROGRAM = 0, 1, 2, 4, 5, 0x80


class LinkError(Exception):
    """The link cannot be opened, or the device does not answer."""


class DeviceException(LinkError):
    """The device answered with a Modbus exception."""

    def __init__(self, message: str, code: int):
        super().__init__(message)
        self.code = code


@dataclass
class LinkStats:
    """Requests of a link and how they ended; one object may count for
    several links in turn (a tool that reconnects keeps its totals)."""

    requests: int = 0
    replies: int = 0
    exceptions: int = 0
    timeouts: int = 0
    lost: int = 0

    def as_dict(self) -> dict[str, int]:
        return asdict(self)


def _quiet_pymodbus() -> None:
    for name in ("pymodbus", "pymodbus.logging"):
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)
        logging.getLogger(name).propagate = False


class ModbusLink:
    """Reads and writes by table and address; ``where`` names the link in
    messages ("127.0.0.1:1502", "/dev/ttyUSB0 unit 17"); ``stats`` counts its
    requests."""

    def __init__(self, client, unit: int, where: str, timeout: float, stats: LinkStats | None = None):
        self.client = client
        self.unit = unit
        self.where = where
        self.timeout = timeout
        self.stats = stats if stats is not None else LinkStats()

    # ------------------------------------------------------------ opening

    @classmethod
    def tcp(cls, host: str, port: int, unit: int = 1, timeout: float = 1.0,
            stats: LinkStats | None = None) -> "ModbusLink":
        _quiet_pymodbus()
        from pymodbus.client import ModbusTcpClient
        client = ModbusTcpClient(host, port=port, timeout=timeout, retries=0)
        where = f"{host}:{port}"
        if not client.connect():
            raise LinkError(f"cannot connect to {where} (nothing listens there, or it refused)")
        return cls(client, unit, where, timeout, stats)

    @classmethod
    def rtu(cls, port: str, baud: int = 19200, parity: str = "N", unit: int = 1,
            timeout: float = 1.0, stats: LinkStats | None = None) -> "ModbusLink":
        _quiet_pymodbus()
        from pymodbus.client import ModbusSerialClient
        par = PARITIES.get(parity.upper())
        if par is None:
            raise LinkError(f"parity '{parity}': give N, E or O")
        client = ModbusSerialClient(port, baudrate=baud, parity=par, bytesize=8, stopbits=1, timeout=timeout,
                                    retries=0)
        where = f"{port} unit {unit}"
        try:
            ok = client.connect()
        except Exception as err:  # pyserial errors come in many types
            raise LinkError(f"cannot open {port}: {err}") from None
        if not ok:
            hint = " (a pty refuses even or odd parity: use --parity N)" if par != "N" else ""
            raise LinkError(f"cannot open {port} at {baud} baud, parity {par}{hint}")
        return cls(client, unit, where, timeout, stats)

    def close(self) -> None:
        try:
            self.client.close()
        except Exception:
            pass

    # ------------------------------------------------------------ requests

    def _call(self, what: str, fn, *args, **kw):
        from pymodbus.exceptions import ConnectionException, ModbusException
        self.stats.requests += 1
        try:
            r = fn(*args, device_id=self.unit, **kw)
        except ConnectionException:
            self.stats.lost += 1
            raise LinkError(f"{what}: the connection to {self.where} is lost") from None
        except ModbusException:
            self.stats.timeouts += 1
            raise LinkError(f"{what}: no reply from {self.where} within {self.timeout:g} s") from None
        except OSError as err:
            self.stats.lost += 1
            raise LinkError(f"{what}: {self.where}: {err.strerror or err}") from None
        self.stats.replies += 1
        if r.isError():
            self.stats.exceptions += 1
            code = getattr(r, "exception_code", 0)
            raise DeviceException(f"{what}: the device refused: {EXCEPTIONS.get(code, 'exception')} "
                                  f"(exception {code:02d})", code)
        return r

    def read(self, table: str, address: int, count: int) -> list:
        c = self.client
        fn = {"coil": c.read_coils, "discrete": c.read_discrete_inputs, "holding": c.read_holding_registers,
              "input": c.read_input_registers}[table]
        r = self._call(f"reading {count} {table} from {address}", fn, address, count=count)
        return list(r.bits[:count]) if table in ("coil", "discrete") else list(r.registers[:count])

    def write_coil(self, address: int, value: bool) -> None:
        self._call(f"writing coil {address}", self.client.write_coil, address, bool(value))

    def write_register(self, address: int, value: int) -> None:
        self._call(f"writing register {address}", self.client.write_register, address, value)

    def write_registers(self, address: int, values: list[int]) -> None:
        self._call(f"writing registers {address}..{address + len(values) - 1}", self.client.write_registers,
                   address, values)

    def identify(self) -> dict[int, str]:
        """The device identification objects (43/14, extended stream)."""
        objects: dict[int, str] = {}
        next_id = 0
        for _ in range(8):
            r = self._call("reading the device identification", self.client.read_device_information,
                           read_code=3, object_id=next_id)
            for k, v in r.information.items():
                objects[int(k)] = v.decode("utf-8", "replace") if isinstance(v, bytes) else str(v)
            if not getattr(r, "more_follows", 0):
                break
            next_id = r.next_object_id
        return objects
