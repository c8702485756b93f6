"""Stimulus CSV files, read as the host board reads them (boards/host/
README.md, "Stimulus CSV"; host_stimulus.c): the same columns, values,
errors (``FILE:LINE: message``) and step-function semantics.

A device ``out`` datum's value holds from its row's time on: it is written
whenever its device is read (at the release of a task that uses it). A
param's or var's value is written once, like a debug or service write, in
the "inputs" phase of the first instant at or after its row's time (after
that instant's publications, before its releases). Columns are bound to
items by name, so a stimulus follows a live replacement of the model.
"""

from __future__ import annotations

import io
import math
import re
from array import array
from bisect import bisect_right
from dataclasses import dataclass, field

from ..board.stimulus_columns import suggestion, unread_items
from ..core import types as T
from ..ir.program import Program
from . import values as V

LINE_MAX = 65536
# Most values (non-empty value cells) of a stimulus: EL_HOST_STIMULUS_MAX_EVENTS
# of boards/host/host_internal.h; a bigger file is reported, not loaded.
MAX_VALUES = 4 * 1024 * 1024
_FLOAT_MAX = float(T.FLOAT32_MAX)
# The grammar of boards/host/README.md, "Stimulus CSV", in ASCII only: Python's
# \d and int() would also take other scripts' digits, which C's reader refuses.
_DECIMAL = re.compile(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?", re.ASCII)
_HEX = re.compile(r"[+-]?0[xX]([0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)([pP][+-]?[0-9]+)?", re.ASCII)
_SPECIAL = re.compile(r"[+-]?(inf|infinity|nan(\([0-9A-Za-z_]*\))?)", re.IGNORECASE | re.ASCII)
_INTEGER = re.compile(r"[+-]?[0-9]+", re.ASCII)
_DIGITS = re.compile(r"[0-9]+", re.ASCII)
_INDEXED = re.compile(r"(.*)\[([0-9]+)\]", re.ASCII | re.DOTALL)


def _whole(digits: str) -> int | None:
    """An ASCII decimal integer (optionally signed), or None beyond 64 bits:
    int() of thousands of digits is refused by Python, and C's strtoll and
    strtoull say ERANGE long before."""
    body = digits.lstrip("+-").lstrip("0")
    return None if len(body) > 20 else int(digits)
_RANGES = {t.name: (t.min, t.max) for t in T.INTEGERS} | {"time": (0, V.TIME_MAX), "bool": (0, 1)}


class StimulusError(Exception):
    """A stimulus file that cannot be used; the message is the host board's
    ``FILE:LINE: message`` (possibly followed by the valid columns)."""


@dataclass
class Column:
    """One stimulus column: which item (by name) and elements it sets, and
    its values over time (non-decreasing times, file order). ``written``
    counts the values of a param or var column already written."""

    name: str
    item: str
    type: T.ValueType  # the item's, which the values were read as
    first: int
    count: int  # elements set: 1, or the item's count for a whole-item column
    times: array = field(default_factory=lambda: array("Q"))  # 8 bytes a row, not a Python int
    values: list = field(default_factory=list)
    written: int = 0
    applied: int = 0  # for a device datum: the rows up to which a read has applied



def parse_strtod(text: str) -> float | None:
    """``text`` read as C's ``strtod`` reads a whole cell, or None."""
    if _DECIMAL.fullmatch(text):
        return float(text)
    if _HEX.fullmatch(text):
        sign = -1.0 if text.startswith("-") else 1.0
        try:
            return sign * float.fromhex(text.lstrip("+-"))
        except OverflowError:  # strtod gives HUGE_VAL and ERANGE
            return sign * math.inf
    if _SPECIAL.fullmatch(text):
        word = text.lstrip("+-").lower()
        value = math.inf if word.startswith("inf") else math.nan
        return -value if text.startswith("-") else value
    return None


class Stimulus:
    """A loaded stimulus file."""

    def __init__(self, path: str, columns: list[Column]):
        self.path = path
        self.columns = columns
        self._by_device: dict[int, list[tuple[Column, int]]] = {}
        self._inputs: list[tuple[Column, int]] = []
        self.unbound: list[str] = []

    def bind(self, program: Program) -> None:
        """Attach the columns to a program's items by name (again after a
        live replacement); columns whose item no longer exists, or changed
        type or size, are listed in ``unbound`` and ignored."""
        by_name = {i.name: i for i in program.items}
        unread = unread_items(program)
        self._by_device, self._inputs, self.unbound = {}, [], []
        for col in self.columns:
            col.applied = 0  # a new program's device data take their values again at their next read
            item = by_name.get(col.item)
            if item is None or item.type != col.type or item.count < col.first + col.count \
                    or item.kind == "dev_in" or item.id in unread:
                self.unbound.append(col.name)
            elif item.kind == "dev_out":
                self._by_device.setdefault(item.device, []).append((col, item.id))
            else:
                self._inputs.append((col, item.id))

    def quiet_until(self, time_us: int) -> int | None:
        """The first time at or after ``time_us`` at which the stimulus may
        write something (None: never again): the next param or var value,
        the next device value, or ``time_us`` itself while a device datum's
        latest value waits for a read to apply it. Before that time, every
        write it would make leaves the items as they are."""
        due = []
        for col, _ in self._inputs:
            if col.written < len(col.times):
                due.append(max(time_us, col.times[col.written]))
        for columns in self._by_device.values():
            for col, _ in columns:
                now = bisect_right(col.times, time_us)
                if col.applied < now:
                    return time_us
                if now < len(col.times):
                    due.append(col.times[now])
        return min(due, default=None)

    def read_device(self, device: int, time_us: int, published: list[list]) -> None:
        """``el_sim_read``: the device's data with a column take the latest
        value whose time is <= time_us."""
        for col, item in self._by_device.get(device, ()):
            self._apply(col, item, time_us, published)

    def apply_inputs(self, time_us: int, published: list[list]) -> None:
        """``el_port_inputs``: every param or var value whose row time is
        <= time_us and that was not written yet is written, in file order."""
        for col, item in self._inputs:
            due = bisect_right(col.times, time_us)
            if due > col.written:
                col.written = due
                self._store(col, item, col.values[due - 1], published)

    def _apply(self, col: Column, item: int, time_us: int, published: list[list]) -> None:
        rows = bisect_right(col.times, time_us)
        col.applied = rows
        if rows:
            self._store(col, item, col.values[rows - 1], published)

    @staticmethod
    def _store(col: Column, item: int, value, published: list[list]) -> None:
        published[item][col.first:col.first + col.count] = [value] * col.count


def load(path: str, program: Program) -> Stimulus:
    """Read and check a stimulus file for ``program``. Raises StimulusError
    (and OSError for an unreadable file)."""
    with open(path, "rb") as f:
        data = f.read()
    reader = _Reader(path, program)
    columns = reader.parse(data)
    stimulus = Stimulus(path, columns)
    stimulus.bind(program)
    return stimulus


class _Reader:
    def __init__(self, path: str, program: Program):
        self.path = path
        self.program = program
        self.line = 0
        self.items = {i.name: i for i in program.items}
        # Local execution simulates every device, as the host board does.
        self.unread = unread_items(program)

    def error(self, message: str, list_columns: bool = False) -> StimulusError:
        text = f"{self.path}:{self.line}: {message}"
        if list_columns:
            text += "\n" + self._valid_columns()
        return StimulusError(text)

    def _valid_columns(self) -> str:
        names = []
        for it in self._columns():
            names.append(it.name if it.count == 1 else f"{it.name} (or {it.name}[0] .. {it.name}[{it.count - 1}])")
        if not names:
            return "  valid columns: time_us (the model has no device `out` data, params or vars that something reads)"
        return "  valid columns: time_us, " + ", ".join(names)

    def _columns(self) -> list:
        """The items a column may name: not device `in` data, and read."""
        return [it for it in self.program.items if it.kind != "dev_in" and it.id not in self.unread]

    def parse(self, data: bytes) -> list[Column]:
        columns: list[Column] | None = None
        last_time = None
        values = 0
        # One line at a time: a list of every line would hold the file twice over.
        for self.line, raw in enumerate(io.BytesIO(data), start=1):
            if raw.endswith(b"\n"):
                raw = raw[:-1]
            if raw.endswith(b"\r"):
                raw = raw[:-1]
            if len(raw) > LINE_MAX:
                raise self.error(f"line longer than {LINE_MAX} bytes")
            if b"\0" in raw:
                raise self.error("NUL byte in line (not a text file?)")
            if self.line == 1 and raw.startswith(b"\xef\xbb\xbf"):
                raw = raw[3:]
            text = raw.decode("utf-8", errors="surrogateescape")
            if not text.strip(" \t"):
                continue
            cells = [c.strip(" \t") for c in text.split(",")]
            if columns is None:
                columns = self._header(cells)
                parsed: list[dict] = [{} for _ in columns]
                continue
            if len(cells) != len(columns) + 1:
                raise self.error(f"{len(cells)} cells, expected {len(columns) + 1} as in the header")
            time_us = _whole(cells[0]) if _DIGITS.fullmatch(cells[0]) else None
            if time_us is None or time_us >= 2 ** 64:
                raise self.error(f"bad time '{cells[0]}' (time_us: whole microseconds, 0 or more)")
            if last_time is not None and time_us < last_time:
                raise self.error(f"time {cells[0]} is before the previous row's time {last_time} "
                                 "(times must not decrease)")
            last_time = time_us
            for col, cell, seen in zip(columns, cells[1:], parsed):
                if cell:
                    # Stimuli repeat their values: each distinct cell of a column is read once.
                    value = seen[cell] if cell in seen else seen.setdefault(cell, self._value(cell, col))
                    if values == MAX_VALUES:
                        raise self.error(f"more than {MAX_VALUES} values: stimulus too big")
                    values += 1
                    col.times.append(time_us)
                    col.values.append(value)
        if columns is None:
            self.line = 1
            raise self.error("empty file: the first line must be the header time_us,DATUM,...")
        return columns

    def _header(self, names: list[str]) -> list[Column]:
        if names[0] != "time_us":
            raise self.error(f"the first column must be time_us, not '{names[0]}'")
        columns: list[Column] = []
        for name in names[1:]:
            col = self._column(name)
            for other in columns:
                if other.item == col.item and other.first < col.first + col.count \
                        and col.first < other.first + other.count:
                    raise self.error(f"columns '{other.name}' and '{name}' set the same datum")
            columns.append(col)
        return columns

    def _column(self, name: str) -> Column:
        if not name:
            raise self.error("empty column name", True)
        item, index = self.items.get(name), None
        if item is None:
            m = _INDEXED.fullmatch(name)
            if m and m.group(1) in self.items:
                # C's reader stops counting past 65535: any index beyond is too big.
                item, index = self.items[m.group(1)], _whole(m.group(2))
                index = 65536 if index is None else min(index, 65536)
        if item is None:
            near = suggestion(name.encode("utf-8", "surrogateescape"),
                              [it.name.encode("utf-8") for it in self._columns()])
            hint = f" (did you mean '{near.decode('utf-8')}'?)" if near is not None else ""
            raise self.error(f"unknown column '{name}'{hint}", True)
        if item.kind == "dev_in":
            raise self.error(f"column '{name}': {item.name} is a device `in` datum; device `out` data, params "
                             "and vars can be given a stimulus", True)
        if index is not None and (item.count == 1 or index >= item.count):
            elements = " (no index)" if item.count == 1 else "s"
            raise self.error(f"column '{name}': {item.name} has {item.count} element{elements}", True)
        if item.id in self.unread:
            raise self.error(f"column '{name}': nothing reads it: {self.unread[item.id]}", True)
        return Column(name, item.name, item.type, index or 0, 1 if index is not None else item.count)

    def _value(self, cell: str, col: Column):
        """The value of a cell of ``col``, within its item's declared range
        (a range the debug and service interfaces also hold writes to)."""
        value = self._typed_value(cell, col.type, col.name)
        bounds = self.items[col.item].range
        if bounds is not None and not bounds[0] <= value <= bounds[1]:
            lo, hi = (f"{b:.9g}" if col.type is T.FLOAT32 else str(int(b)) for b in bounds)
            raise self.error(f"value {cell} out of range for column '{col.name}' "
                             f"(the declared range of {col.item}: {lo} .. {hi})")
        return value

    def _typed_value(self, cell: str, t: T.ValueType, column: str):
        if t is T.BOOL:
            if cell in ("1", "true"):
                return True
            if cell in ("0", "false"):
                return False
            raise self.error(f"bad value '{cell}' for column '{column}' (bool: 0, 1, true or false)")
        if t is T.FLOAT32:
            return self._float(cell, column)
        if not _INTEGER.fullmatch(cell):
            what = ": whole milliseconds" if t is T.TIME else ": a decimal integer"
            raise self.error(f"bad number '{cell}' for column '{column}' ({t.name}{what})")
        lo, hi = _RANGES[t.name]
        value = _whole(cell)
        if value is None or not lo <= value <= hi:
            raise self.error(f"value {cell} out of range for column '{column}' ({t.name}: {lo} .. {hi})")
        return value

    def _float(self, cell: str, column: str) -> float:
        d = parse_strtod(cell)
        if d is None:
            raise self.error(f"bad number '{cell}' for column '{column}' (float32)")
        overflow = math.isinf(d) and not _SPECIAL.fullmatch(cell)
        # Above FLT_MAX but below FLT_MAX + half an ulp rounds to FLT_MAX.
        if overflow or (math.isfinite(d) and abs(d) >= _FLOAT_MAX + 2.0 ** 103):
            raise self.error(f"value '{cell}' out of range for column '{column}' "
                             f"(float32: magnitude at most {_FLOAT_MAX:.9g})")
        if math.isfinite(d) and abs(d) > _FLOAT_MAX:
            d = math.copysign(_FLOAT_MAX, d)
        return V.f32(d)
