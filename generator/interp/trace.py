"""Traces in the host board's CSV and VCD formats, byte for byte
(boards/host/README.md, "Traces"; host_trace.c).

A trace has one column per element of every item (params, vars, device
data, in item order) and one per chart (its steps' activity). At every
instant the engine hands over a snapshot: one canonical value per column
(bool as 0/1, integers as ints, ``float32`` as its bit pattern with one NaN
per sign, a chart as a tuple of 0/1 flags), so that equal snapshots mean
equal printed values, as the host compares bytes.

The columns are fixed when the trace opens. After a live replacement the
:class:`Sampler` binds them to the new program by name; a column whose item
or chart is gone keeps its last value, and new items are not traced.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from ..board import handlers as H
from ..core import types as T
from ..ir.program import Program
from . import values as V

_NAN_BITS = {False: 0x7FC00000, True: 0xFFC00000}  # C's NAN and -NAN


class TraceError(Exception):
    """A trace that cannot be written; one line, as the host board says it."""


@dataclass(frozen=True)
class TraceColumn:
    """One traced column: an element of an item or of a device's state
    field, or a chart's activity."""

    kind: str  # "item" | "state" | "chart"
    name: str  # the item's, the state field's (DEVICE.FIELD) or the chart's name
    element: int | None = None  # for an item with count > 1
    type: T.ValueType | None = None
    steps: tuple[str, ...] = ()

    @property
    def csv_name(self) -> str:
        if self.kind == "chart":
            return f"{self.name}.active"
        return self.name if self.element is None else f"{self.name}[{self.element}]"

    @property
    def vcd_name(self) -> str:
        if self.kind == "chart":
            return f"{_vcd_name(self.name)}.active"
        return _vcd_name(self.name) + ("" if self.element is None else f"({self.element})")


def columns_of(program: Program, states: bool = False) -> list[TraceColumn]:
    """The columns of a program's trace, in the host board's order; with
    ``states`` (``--trace-state``) the `state` fields of the devices running
    host handlers come between the items and the charts."""
    cols = []
    for item in program.items:
        for e in range(item.count):
            cols.append(TraceColumn("item", item.name, e if item.count > 1 else None, item.type))
    if states:
        for dev, name, t, count, _addr in H.state_items(program, "host"):
            for e in range(count):
                cols.append(TraceColumn("state", f"{dev.path}.{name}", e if count > 1 else None, t))
    for chart in program.charts:
        cols.append(TraceColumn("chart", chart.name, steps=tuple(s.name for s in chart.steps)))
    return cols


def canonical(t: T.ValueType) -> Callable:
    """The snapshot form of a value of type ``t``."""
    if t is T.BOOL:
        return lambda v: 1 if v else 0
    if t is T.FLOAT32:
        return lambda v: _NAN_BITS[math.copysign(1.0, v) < 0] if v != v else V.f32_bits(v)
    return lambda v: v


class Sampler:
    """Takes snapshots of a running program for a fixed list of columns."""

    def __init__(self, columns: list[TraceColumn]):
        self.columns = columns
        self.last: tuple | None = None
        self._getters: list[Callable[[], object]] = []

    def bind(self, program: Program, published: list[list], charts: list, devices=None) -> list[str]:
        """Read the columns from ``published`` (item values by id),
        ``charts`` (objects with ``chart`` and ``active``) and ``devices``
        (interp.devices.ModelDevices, for state columns) of ``program``.
        Returns the names of columns that now hold their last value."""
        items = {i.name: i for i in program.items}
        fields = devices.state_fields() if devices is not None else {}
        chart_by_name = {c.chart.name: c for c in charts}
        getters, frozen = [], []
        for index, col in enumerate(self.columns):
            getter = None
            if col.kind == "item":
                item = items.get(col.name)
                element = col.element or 0
                if item is not None and item.type == col.type and (item.count > 1) == (col.element is not None) \
                        and element < item.count:
                    getter = _item_getter(published, item.id, element, canonical(col.type))
            elif col.kind == "state":
                field = fields.get(col.name)
                element = col.element or 0
                if field is not None and field[0] == col.type and element < len(field[1]):
                    getter = _item_getter([field[1]], 0, element, canonical(col.type))
            elif col.name in chart_by_name:
                getter = _chart_getter(chart_by_name[col.name], col.steps)
            if getter is None:
                frozen.append(col.csv_name)
                getter = _frozen_getter(self, index, col)
            getters.append(getter)
        self._getters = getters
        return frozen

    def snapshot(self) -> tuple:
        values = tuple(g() for g in self._getters)
        self.last = values
        return values


def _item_getter(published, item_id, element, canon):
    return lambda: canon(published[item_id][element])


def _chart_getter(runner, step_names):
    index = {s.name: i for i, s in enumerate(runner.chart.steps)}
    positions = [index.get(name) for name in step_names]
    return lambda: tuple(1 if p is not None and runner.active[p] else 0 for p in positions)


def _frozen_getter(sampler: Sampler, index: int, col: TraceColumn):
    if sampler.last is not None:
        value = sampler.last[index]
    else:
        value = (0,) * len(col.steps) if col.kind == "chart" else canonical(col.type)(V.zero(col.type))
    return lambda: value


# ====================================================================== writers


def _vcd_name(text: str) -> str:
    """A VCD reference: bytes that are blank, control or not ASCII become '_'."""
    return "".join(chr(b) if ord(" ") < b <= ord("~") else "_" for b in text.encode("utf-8"))


def _vcd_id(k: int) -> str:
    """The identifier code of column k: base 94 over '!' .. '~', low digit first."""
    digits = []
    while True:
        digits.append(chr(ord("!") + k % 94))
        k //= 94
        if k == 0 or len(digits) == 7:
            return "".join(digits)


def _float_text(bits: int) -> str:
    """``%.9g`` of a float32 as glibc prints it; every NaN as ``nan`` (its
    sign depends on the compiler, not on the model: boards/host/host_trace.c)."""
    value = V.f32_from_bits(bits)
    if value != value:
        return "nan"
    return "%.9g" % value


class TraceWriter:
    """Writes the host board's CSV or VCD trace (by the path's extension)."""

    def __init__(self, path: str, program: Program, columns: list[TraceColumn]):
        lower = path.lower()
        if len(path) > 4 and lower.endswith(".csv"):
            self.format = "csv"
        elif len(path) > 4 and lower.endswith(".vcd"):
            self.format = "vcd"
        else:
            raise TraceError(f"--trace {path}: unknown trace format (give a .csv or a .vcd file)")
        self.path = path
        self.columns = columns
        self.ids = [_vcd_id(k) for k in range(len(columns))]
        try:
            self.file = open(path, "w", encoding="utf-8", newline="\n", buffering=65536)
        except OSError as err:
            raise TraceError(f"cannot write trace {path}: {err.strerror or err}") from None
        self.previous: tuple | None = None
        self.last_time_us = 0
        self._vcd_at: int | None = None  # the time of the last `#time` line of a VCD
        if self.format == "csv":
            self.file.write(",".join(["time_us"] + [c.csv_name for c in columns]) + "\n")
        else:
            self._vcd_header(program)

    def record(self, time_us: int, snapshot: tuple) -> None:
        """The values at one instant."""
        if self.format == "csv":
            if snapshot != self.previous:
                self.file.write(f"{time_us}," + ",".join(self._csv_cell(c, v)
                                                           for c, v in zip(self.columns, snapshot)) + "\n")
        elif self.previous is None:
            self._vcd_at = time_us
            self.file.write(f"#{time_us}\n$dumpvars\n")
            self.file.write("".join(self._vcd_value(k, v) for k, v in enumerate(snapshot)))
            self.file.write("$end\n")
        else:
            changes = "".join(self._vcd_value(k, v) for k, (v, old) in enumerate(zip(snapshot, self.previous))
                              if v != old)
            if changes:
                self._vcd_at = time_us
                self.file.write(f"#{time_us}\n{changes}")
        self.previous = snapshot
        self.last_time_us = time_us

    def event(self, time_us: int, name: str, value: int) -> None:
        """A status event (boards/host/README.md, "Traces"): the status item
        ``name`` (a link's fault counter) reads ``value`` from ``time_us``
        on. A line of its own, never a column, so that a run without faults
        has the trace of every other board and mode: in CSV
        ``#status,TIME,NAME,VALUE``, in VCD a ``$comment`` at that time."""
        if self.format == "csv":
            self.file.write(f"#status,{time_us},{name},{value}\n")
            return
        if self._vcd_at != time_us:
            self.file.write(f"#{time_us}\n")
            self._vcd_at = time_us
        self.file.write(f"$comment status {_vcd_name(name)} {value} $end\n")

    def close(self, end_time_us: int | None = None) -> None:
        """Flush and close; a VCD ends with ``#end_time_us`` (the end of the
        last traced tick) when anything was recorded."""
        if self.file.closed:
            return
        try:
            if self.format == "vcd" and self.previous is not None and end_time_us is not None:
                self.file.write(f"#{end_time_us}\n")
            self.file.close()
        except OSError as err:
            raise TraceError(f"error writing trace {self.path}: {err.strerror or err}") from None

    # ------------------------------------------------------------ formats

    @staticmethod
    def _csv_cell(col: TraceColumn, value) -> str:
        if col.kind == "chart":
            return "+".join(name for name, on in zip(col.steps, value) if on)
        if col.type is T.FLOAT32:
            return _float_text(value)
        return str(value)

    def _vcd_header(self, program: Program) -> None:
        out = [f"$comment EasyLab trace of model {program.name}, program id 0x{program.program_id:08x}, "
               f"tick {program.tick_us} us $end\n",
               f"$timescale 1us $end\n$scope module {_vcd_name(program.name or 'model')} $end\n"]
        for col, ident in zip(self.columns, self.ids):
            if col.kind == "chart":
                if col.steps:
                    out.append(f"$var wire {len(col.steps)} {ident} {col.vcd_name} $end\n")
            elif col.type is T.FLOAT32:
                out.append(f"$var real 64 {ident} {col.vcd_name} $end\n")
            else:
                out.append(f"$var wire {_bit_width(col.type)} {ident} {col.vcd_name} $end\n")
        out.append("$upscope $end\n$enddefinitions $end\n")
        self.file.write("".join(out))

    def _vcd_value(self, k: int, value) -> str:
        col, ident = self.columns[k], self.ids[k]
        if col.kind == "chart":
            if not col.steps:
                return ""
            if len(col.steps) == 1:
                return f"{value[0]}{ident}\n"
            return "b" + "".join(str(f) for f in reversed(value)) + f" {ident}\n"
        if col.type is T.FLOAT32:
            return f"r{_float_text(value)} {ident}\n"
        if col.type is T.BOOL:
            return f"{value}{ident}\n"
        width = _bit_width(col.type)
        return f"b{value & ((1 << width) - 1):0{width}b} {ident}\n"


def _bit_width(t: T.ValueType) -> int:
    return 1 if t is T.BOOL else t.bits
