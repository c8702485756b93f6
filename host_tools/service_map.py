"""A service map (``service_map.json``, written by ``easylab build``) and the
conversion of its items' values to and from Modbus registers.

Registers are big-endian 16-bit words; 32-bit values (int32, uint32, time,
float32) take two registers, the high word first; int8 is sign-extended;
bool items are coils or discrete inputs (docs/service.md).
"""

from __future__ import annotations

import json
import math
import re
import struct
from dataclasses import dataclass
from pathlib import Path

from .map_schema import SERVICE_MAP_SCHEMA, MapFileError, read_map
from .units import Scale, ScaleError

MAP_FORMAT = 1
READ_TABLES = ("coil", "discrete", "holding", "input")
_INT_LIMITS = {"int8": (-128, 127), "uint8": (0, 255), "int16": (-32768, 32767), "uint16": (0, 65535),
               "int32": (-2 ** 31, 2 ** 31 - 1), "uint32": (0, 2 ** 32 - 1), "time": (0, 2 ** 32 - 1)}
_FLOAT32_MAX = 3.4028234663852886e38
_TIME_UNITS = {"ms": 1, "s": 1000, "min": 60000, "m": 60000, "h": 3600000}
_ALARM_WORDS = re.compile(r"(^|_)(alarm|fault|error|trip)(_|$)", re.IGNORECASE)


class MapError(Exception):
    """A map file that cannot be used; the message is one line."""


class ValueError_(ValueError):
    """A value that is not one of the item's type; the message is one line."""


@dataclass(frozen=True)
class ServiceItem:
    id: int
    name: str
    kind: str
    table: str
    address: int
    registers: int
    type: str
    unit: str | None
    range: tuple | None
    access: str
    persist: bool
    scale: Scale = Scale()  # stored integer x scale = the engineering value

    @property
    def writable(self) -> bool:
        return self.access == "rw"

    @property
    def is_bit(self) -> bool:
        return self.table in ("coil", "discrete")

    @property
    def end(self) -> int:
        return self.address + self.registers

    # ------------------------------------------------------------ text

    @property
    def alarm(self) -> bool:
        """An alarm, drawn as one when it is on (non-zero): a fault counter
        (status item), or a bool measurement named for one (alarm,
        motor_fault, over_temp_trip: a word alarm, fault, error or trip)."""
        if self.kind == "status":
            return True
        return self.type == "bool" and self.access == "ro" and bool(_ALARM_WORDS.search(self.name))

    @property
    def scaled(self) -> bool:
        return not self.scale.is_one

    def parse(self, text: str):
        """A value of this item from text, in engineering units (a scaled
        item's text is converted back to its stored integer, exactly)."""
        if not self.scaled:
            return self.parse_stored(text)
        try:
            value = self.scale.stored(text)
        except ScaleError as err:
            raise ValueError_(f"'{self.name}': {err}") from None
        lo, hi = _INT_LIMITS[self.type]
        if not lo <= value <= hi:
            raise ValueError_(f"{text.strip()} does not fit '{self.name}' ({self.type} x {self.scale.text()}: "
                              f"{self.format(lo)}..{self.format(hi)}{' ' + self.unit if self.unit else ''})")
        return value

    def parse_stored(self, text: str):
        """A value of this item from text, in stored units (``time``: whole
        milliseconds, or with a unit: 2s, 500ms, 1.5min)."""
        t = text.strip()
        if self.type == "bool":
            low = t.lower()
            if low in ("1", "true", "on", "yes"):
                return True
            if low in ("0", "false", "off", "no"):
                return False
            raise ValueError_(f"'{text}' is not a bool for '{self.name}' (give 0/1, true/false, on/off)")
        if self.type == "float32":
            try:
                value = float(t)
            except ValueError:
                raise ValueError_(f"'{text}' is not a number for '{self.name}' (float32)") from None
            if not math.isfinite(value) or abs(value) > _FLOAT32_MAX:
                raise ValueError_(f"{text} is not a finite float32 for '{self.name}'")
            return value
        if self.type == "time":
            m = re.fullmatch(r"(\d+(?:\.\d+)?)\s*(ms|s|min|m|h)?", t)
            if not m:
                raise ValueError_(f"'{text}' is not a time for '{self.name}' (milliseconds, or 2s, 500ms, 1min)")
            ms = float(m.group(1)) * _TIME_UNITS[m.group(2) or "ms"]
            if ms != int(ms):
                raise ValueError_(f"{text} is not a whole number of milliseconds for '{self.name}'")
            value = int(ms)
        else:
            try:
                value = int(t, 0)
            except ValueError:
                raise ValueError_(f"'{text}' is not an integer for '{self.name}' ({self.type})") from None
        lo, hi = _INT_LIMITS[self.type]
        if not lo <= value <= hi:
            raise ValueError_(f"{value} does not fit '{self.name}' ({self.type}: {lo}..{hi})")
        return value

    def format(self, value) -> str:
        """A stored value as text in engineering units."""
        if self.type == "bool":
            return "1" if value else "0"
        if self.type == "float32":
            return f"{value:.9g}"
        return self.scale.show(int(value))

    def describe_range(self) -> str:
        if self.range is None:
            return self.type
        lo, hi = self.range
        return f"{self.format(lo)}..{self.format(hi)}{' ' + self.unit if self.unit else ''}"

    # ------------------------------------------------------------ registers

    def to_registers(self, value) -> list[int]:
        if self.type == "float32":
            raw = struct.unpack(">I", struct.pack(">f", float(value)))[0]
        else:
            raw = int(value) & (0xFFFFFFFF if self.registers == 2 else 0xFFFF)
        if self.registers == 2:
            return [raw >> 16, raw & 0xFFFF]
        return [raw]

    def from_registers(self, regs: list[int]):
        if self.type == "float32":
            return struct.unpack(">f", struct.pack(">HH", regs[0], regs[1]))[0]
        if self.registers == 2:
            raw = (regs[0] << 16) | regs[1]
            return raw - (1 << 32) if self.type == "int32" and raw & 0x80000000 else raw
        raw = regs[0]
        if self.type in ("int8", "int16") and raw & 0x8000:
            return raw - 0x10000
        return raw


@dataclass
class ServiceMap:
    path: str
    model: str
    title: str | None
    program_id: str
    interfaces: dict
    items: list[ServiceItem]

    def item(self, name: str) -> ServiceItem:
        for it in self.items:
            if it.name == name:
                return it
        import difflib
        close = difflib.get_close_matches(name, [i.name for i in self.items], n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise MapError(f"'{name}' is not a service item of model '{self.model}'{hint}")

    def params(self) -> list[ServiceItem]:
        """The writable params: what backup and restore save."""
        return [i for i in self.items if i.kind == "param" and i.writable]


def load_map(path: str | Path) -> ServiceMap:
    """The service map in the file at ``path``, valid against
    map_schema.SERVICE_MAP_SCHEMA; otherwise :class:`MapError` in one line."""
    try:
        data = read_map(path, SERVICE_MAP_SCHEMA, f"service map of format {MAP_FORMAT}",
                        "no such map file (easylab build writes service_map.json beside the firmware)")
    except MapFileError as err:
        raise MapError(str(err)) from None
    items = [ServiceItem(i["id"], i["name"], i.get("kind", "param"), i["table"], i["address"], i["registers"],
                         i["type"], i.get("unit"), tuple(i["range"]) if i.get("range") is not None else None,
                         i["access"], i.get("persist", False), Scale.of(i.get("scale")))
             for i in data["items"]]
    return ServiceMap(str(path), data.get("model", "?"), data.get("title"), data.get("program_id", "?"),
                      data.get("interfaces", {}), items)


def read_groups(items: list[ServiceItem], max_regs: int = 125, max_bits: int = 2000) -> list[list[ServiceItem]]:
    """Items grouped into requests: same table, adjacent addresses (the slave
    refuses ranges with holes), within the specification's quantities."""
    groups: list[list[ServiceItem]] = []
    for it in sorted(set(items), key=lambda i: (READ_TABLES.index(i.table), i.address)):
        g = groups[-1] if groups else None
        limit = max_bits if it.is_bit else max_regs
        if g and g[-1].table == it.table and g[-1].end == it.address and it.end - g[0].address <= limit:
            g.append(it)
        else:
            groups.append([it])
    return groups
