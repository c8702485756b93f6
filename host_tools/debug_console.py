"""``easylab-debug``: the debug console (docs/protocol.md).

    easylab-debug [--map debug_map.json] URL              interactive
    easylab-debug --map M URL -c "read temperature; stack"
    easylab-debug --map M URL --script FILE [--json]
    easylab-debug web --map M TARGET [--listen ADDR:PORT]   the online mode (docs/online.md)

URL is anything pyserial opens: a device (/dev/ttyUSB0), a pty or its
link, ``socket://127.0.0.1:PORT``. The console refuses a firmware whose
program id differs from the map's. Failures are one line on stderr
(``easylab-debug: error: ...``), never a traceback. Exit status: 0 done,
1 a command or the connection failed, 2 bad usage or the wrong map.
"""

from __future__ import annotations

import argparse
import cmd
import json
import os
import re
import shlex
import struct
import sys
import threading
import time
from pathlib import Path

from .debug_map import DebugMap, Item, MapError
from .debug_protocol import (K, OP_NAMES, OPS, STEP_UNITS, TYPES, DebugClient, DebugError, ProtocolError, decode_value,
                             type_size)
from .transport import TransportError
from .units import ScaleError

PROG = "easylab-debug"
EXIT_OK, EXIT_FAIL, EXIT_USAGE = 0, 1, 2

COMMANDS = {
    "info": "info                      the firmware, the map and the program's state",
    "vars": "vars [GLOB]               items (params, vars, device data, actor states, charts' state)",
    "read": "read NAME...              NAME = VALUE per item (NAME[i]: one element; Chart: its active steps, "
            "Chart.Step.time: ms since the step was entered)",
    "write": "write NAME VALUE          write an item (at the next instant; at once when halted at one)",
    "watch": "watch NAME... [--every 100ms] [--count N]   a live table (Ctrl-C ends it)",
    "tx": "tx begin|commit|abort     a transaction: reads and writes queued, applied at one instant",
    "stack": "stack                     running task, active steps of every chart, where it halted",
    "run": "run                       let a halted program go on",
    "break": "break | break at ITEM | break when ITEM OP VALUE   halt at the next instant | set a breakpoint "
             "(step, transition, actor, task) | halt at the instant where ITEM OP VALUE turns true "
             "(OP: == != < <= > >=)",
    "step": "step [task|chart|actor|instant]   one task activation (default), actor firing or instant; "
            "chart: to the end of the next chart evolution, showing the steps it entered",
    "reset": "reset [--halt]            restart the firmware from boot (--halt: halted at its first instant)",
    "load": "load FILE                 replace the running model with FILE (local execution: `easylab run`)",
    "delete": "delete N|all              remove breakpoint N",
    "force": "force NAME VALUE          hold a param, var or device datum (a sensor) at VALUE every instant",
    "release": "release NAME|all          stop forcing NAME (or every forced item): the program and the "
               "stimulus change it again",
    "forced": "forced                    the forced items and their values",
    "breakpoints": "breakpoints [--all]       the breakpoints (--all: every place one can go)",
    "wait": "wait [TIMEOUT]            wait until the program halts (default 10s); every halt shows the "
            "element, its file:line and the logical time in ms",
    "counters": "counters                  the firmware's frame and error counters",
    "sleep": "sleep DURATION            pause a script (100ms, 2s)",
    "quit": "quit                      leave (also: exit, Ctrl-D)",
}


# A firmware built without slots for forcing or conditional breakpoints (HELLO reports 0).
_NO_SLOTS = ("this firmware has no {what}: declare slots in the model (`debug on ... {setting} N`, "
             "docs/protocol.md) and rebuild it")


def no_slots(what: str, setting: str) -> str:
    """Why a firmware without slots (HELLO reports 0) cannot do `what`
    (forcing, conditional breakpoints), and the model's `setting` that asks."""
    return _NO_SLOTS.format(what=what, setting=setting)


def describe_comparison(it: Item, b) -> str:
    """A conditional breakpoint's ``NAME OP VALUE``: its comparison from the
    breakpoint list (BP_LIST), the constant as the item shows values."""
    name = f"{it.name}[{b.b}]" if it.count > 1 else it.name
    value = decode_value(it.type, b.value[:type_size(it.type)])
    return f"{name} {OP_NAMES.get(b.op, '?')} {format_value(it, value)}"


class CommandError(Exception):
    """A command that cannot be done: one line for the user."""


def parse_duration(text: str) -> float:
    """Seconds from ``100ms``, ``2s``, ``1.5s``, ``250us``, ``1m``."""
    m = re.fullmatch(r"\s*(\d+(?:\.\d*)?)\s*(us|ms|s|m|min)?\s*", text)
    if not m:
        raise CommandError(f"'{text}' is not a duration (100ms, 2s, 1.5s)")
    scale = {"us": 1e-6, "ms": 1e-3, "s": 1.0, "m": 60.0, "min": 60.0, None: 1.0}[m.group(2)]
    return float(m.group(1)) * scale


def parse_value(item: Item, text: str):
    """A value of the item's type from the user's text, checked (a scaled
    item's text is in engineering units, converted back exactly)."""
    t = item.type
    if not item.scale.is_one:
        try:
            text = str(item.scale.stored(text))
        except ScaleError as err:
            raise CommandError(f"{item.name}: {err}") from None
    low = text.strip().lower()
    if t == "bool":
        if low in ("1", "true", "on", "yes"):
            return True
        if low in ("0", "false", "off", "no"):
            return False
        raise CommandError(f"{item.name} is a bool: give 0, 1, true or false, not '{text}'")
    if t == "float32":
        try:
            return float(text)
        except ValueError:
            raise CommandError(f"{item.name} is a float32: '{text}' is not a number") from None
    if t == "time":
        m = re.fullmatch(r"(\d+(?:\.\d+)?)\s*(ms|s|m|h)?", low)
        if not m:
            raise CommandError(f"{item.name} is a time: give milliseconds or a duration (500ms, 2s), not '{text}'")
        ms = float(m.group(1)) * {"ms": 1, "s": 1000, "m": 60000, "h": 3600000, None: 1}[m.group(2)]
        if ms != int(ms) or not 0 <= ms <= 0xFFFFFFFF:
            raise CommandError(f"{item.name}: {text} is not a whole number of milliseconds within 0..4294967295")
        return int(ms)
    try:
        v = int(text, 0)
    except ValueError:
        raise CommandError(f"{item.name} is an {t}: '{text}' is not an integer") from None
    fmt = TYPES[t][1]
    bits = struct.calcsize(fmt) * 8
    lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if fmt[1].islower() else (0, (1 << bits) - 1)
    if not lo <= v <= hi:
        raise CommandError(f"{item.name} is an {t}: {format_value(item, v)} is outside "
                           f"{format_value(item, lo)}..{format_value(item, hi)}")
    return v


def step_names(item: Item, value):
    """A chart's active steps by name (None for a branch in no step); any
    other item's value as it is."""
    if item.labels is None:
        return value
    if isinstance(value, list):
        return [step_names(item, v) for v in value]
    return item.labels.get(value, str(value))


def format_value(item: Item, value) -> str:
    if item.labels is not None:  # a chart's active steps `A + B`, its last transition `A -> B`; `(none)`
        names = step_names(item, value if isinstance(value, list) else [value])
        return " + ".join(n for n in names if n is not None) or "(none)"
    if isinstance(value, list):
        return "[" + ", ".join(format_value(item, v) for v in value) + "]"
    if item.type == "bool":
        return "true" if value else "false"
    if item.type == "float32":
        return f"{value:.9g}"
    if not item.scale.is_one:  # engineering units: 1628 at scale 0.1 "degC" is "162.8 degC"
        return item.scale.show(value) + (f" {item.unit}" if item.unit else "")
    return str(value)


class Session:
    """The console's commands over one connection. Output goes through
    ``emit`` (text, or one JSON object per line with --json)."""

    def __init__(self, client: DebugClient, dmap: DebugMap | None, url: str, json_mode: bool = False,
                 out=None, interactive: bool = False):
        self.c = client
        self.map = dmap
        self.url = url
        self.json = json_mode
        self.out = out or sys.stdout
        self.interactive = interactive
        self.lock = threading.RLock()
        self.tx_reads: list[tuple[Item, int | None]] = []
        self.in_tx = False
        self._info_cache: dict[int, Item] = {}

    # -------------------------------------------------------------- output

    def emit(self, text: str, obj: dict | None = None) -> None:
        if self.json:
            if obj is not None:
                self.out.write(json.dumps(obj) + "\n")
        else:
            self.out.write(text + "\n")
        self.out.flush()

    # -------------------------------------------------------------- names

    def item(self, name: str) -> tuple[Item, int | None]:
        """An item by name (or #ID), with an element index from NAME[i]."""
        elem = None
        m = re.fullmatch(r"(.+)\[(\d+)\]", name)
        if m and (self.map is None or m.group(1) in self.map.by_name or m.group(1).startswith("#")):
            name, elem = m.group(1), int(m.group(2))
        if self.map is not None:
            try:
                it = self.map.item(name)
            except MapError as err:
                raise CommandError(str(err)) from None
        else:
            m = re.fullmatch(r"#?(\d+)", name)
            if not m:
                raise CommandError(f"without --map items are named by id: #0, #1, ... (not '{name}')")
            it = self._item_by_id(int(m.group(1)))
        if elem is not None and elem >= it.count:
            raise CommandError(f"{it.name} has {it.count} element(s): no [{elem}]")
        return it, elem

    def _item_by_id(self, ident: int) -> Item:
        if ident not in self._info_cache:
            with self.lock:
                info = self.c.item_info(ident)
            self._info_cache[ident] = Item(ident, f"#{ident}", info["kind"], info["type"], info["count"],
                                           info["flags"], None, info.get("range"))
        return self._info_cache[ident]

    def all_items(self) -> list[Item]:
        if self.map is not None:
            return self.map.items
        return [self._item_by_id(i) for i in range(self.c.hello_info.item_count)]

    def where(self, loc, bp, tick: int | None = None) -> str:
        """Where the program halted: the element and, with a map, its
        ``file:line`` in the model (an instant: the tasks it releases at
        ``tick``)."""
        if loc.kind == K.P_NONE:
            return "?"
        if loc.kind == K.P_CONDITION:
            return self.condition_text(loc.a, loc.b, bp)
        if self.map is None:
            return (f"breakpoint {bp} at " if bp is not None else "") + f"{loc.kind_name} {loc.a}.{loc.b}"
        text = self.map.describe(loc.kind, loc.a, loc.b)
        source = self.map.location(loc.kind, loc.a, loc.b)
        if source is not None:
            text += f" ({source})"
        elif loc.kind == K.P_INSTANT and tick is not None:
            tasks = self.map.released(tick)
            if tasks:
                text += " (releases " + ", ".join(f"task {t['name']} at {t.get('location', '?')}"
                                                   for t in tasks) + ")"
        return (f"breakpoint {bp} at " if bp is not None else "") + text

    def condition_text(self, item_id: int, elem: int, bp: int | None) -> str:
        """Where a conditional breakpoint halted: ``breakpoint N when NAME
        OP VALUE (file:line)``, its comparison from the breakpoint list."""
        with self.lock:
            found = next((b for b in self.c.bp_list() if b.slot == bp), None) if bp is not None else None
        if found is None:
            it = self._item_named(item_id)
            return f"condition on {it.name}" + (f"[{elem}]" if it.count > 1 else "")
        return f"breakpoint {bp} when {self.describe_condition(found)}"

    def describe_condition(self, b) -> str:
        """A conditional breakpoint's ``NAME OP VALUE (file:line)``."""
        source = self.map.location(K.P_CONDITION, b.a, b.b) if self.map is not None else None
        return describe_comparison(self._item_named(b.a), b) + (f" ({source})" if source else "")

    def _item_named(self, item_id: int) -> Item:
        if self.map is not None and item_id in self.map.by_id:
            return self.map.by_id[item_id]
        return self._item_by_id(item_id)

    def when(self, tick: int) -> str:
        """The logical time of a tick: milliseconds with a map (tick_us),
        and the tick."""
        return f"{self.map.ms(tick)} ms (tick {tick})" if self.map is not None and self.map.tick_us else f"tick {tick}"

    def halt_obj(self, f) -> dict:
        """A halt for --json: why, where, the element's file:line, the time."""
        loc = f.location
        return {"halted": True, "why": f.why, "at": self.where(loc, f.breakpoint, f.tick), "tick": f.tick,
                "ms": float(self.map.ms(f.tick)) if self.map is not None and self.map.tick_us else None,
                "location": self.map.location(loc.kind, loc.a, loc.b) if self.map is not None else None}

    def halt_text(self, f) -> str:
        """``halted (WHY) at ELEMENT (FILE:LINE), T ms (tick N)``."""
        return f"halted ({f.why}) at {self.where(f.location, f.breakpoint, f.tick)}, {self.when(f.tick)}"

    # -------------------------------------------------------------- commands

    def cmd_info(self, args):
        with self.lock:
            h = self.c.hello_info or self.c.hello()
            f = self.c.flags()
        state = self.halt_text(f) if f.halted else "running"
        obj = {"url": self.url, "model": self.map.model if self.map else None, "program_id": f"0x{h.program_id:08x}",
               "protocol": h.version, "max_frame": h.max_frame, "items": h.item_count, "actors": h.actor_count,
               "charts": h.chart_count, "tasks": h.task_count, "tick": f.tick, "halted": f.halted,
               "state": state, "map": self.map.path if self.map else None}
        lines = [f"firmware    {self.url}: program 0x{h.program_id:08x}, debug protocol {h.version}, "
                 f"frames up to {h.max_frame} bytes",
                 f"model       {self.map.model if self.map else '? (no --map)'}"
                 + (f" ({self.map.path})" if self.map else ""),
                 f"contents    {h.item_count} items, {h.actor_count} actors, {h.chart_count} charts, "
                 f"{h.task_count} tasks",
                 f"state       {state}" + ("" if f.halted else f", {self.when(f.tick)}")]
        if f.status & K.S_FORCED:
            with self.lock:
                names = [self._forced_name(x) for x in self.c.forced()]
            obj["forced"] = names
            lines.append(f"forced: {', '.join(names)}")
        self.emit("\n".join(lines), obj)

    def _forced_name(self, forced) -> str:
        it = self._item_named(forced.item)
        return f"{it.name}[{forced.elem}]" if it.count > 1 else it.name

    def cmd_vars(self, args):
        if len(args) > 1:
            raise CommandError("usage: vars [GLOB]")
        items = self.map.glob(args[0] if args else None) if self.map else self.all_items()
        if args and not items:
            raise CommandError(f"no item matches '{args[0]}'")
        width = max((len(i.name) for i in items), default=4)
        for i in items:
            count = f"[{i.count}]" if i.count > 1 else ""
            shown = str if i.scale.is_one else i.scale.show  # a scaled item's range in engineering units
            rng = f" {shown(i.range[0])}..{shown(i.range[1])}" if i.range else ""
            unit = f" unit \"{i.unit}\"" if i.unit else ""
            unit += f" scale {i.scale.text()}" if not i.scale.is_one else ""
            text = (f"{i.name:<{width}}  {i.type + count:<10} {i.kind:<8} {'rw' if i.writable else 'ro'}"
                    f"{rng}{unit}  #{i.id}  {i.location}")
            self.emit(text, {"id": i.id, "name": i.name, "type": i.type, "count": i.count, "kind": i.kind,
                             "writable": i.writable, "unit": i.unit, "range": i.range, "location": i.location})

    def _read_values(self, targets):
        with self.lock:
            values = self.c.read([(it.id, it.type, it.count) for it, _ in targets])
        return [v[e] if e is not None else v for (it, e), v in zip(targets, values)]

    def cmd_read(self, args):
        if not args:
            raise CommandError("usage: read NAME...")
        targets = [self.item(a) for a in args]
        if self.in_tx:
            with self.lock:
                for it, elem in targets:
                    self.c.read_raw([it.id])
                    self.tx_reads.append((it, elem))
                    self.emit(f"{it.name} queued for the commit", {"name": it.name, "queued": True})
            return
        for (it, elem), v in zip(targets, self._read_values(targets)):
            name = f"{it.name}[{elem}]" if elem is not None else it.name
            self.emit(f"{name} = {format_value(it, v)}", {"name": name, "value": step_names(it, v)})

    def _value_to_set(self, args, verb: str, read_only: str):
        """`VERB NAME VALUE`'s item, element and stored value, checked as a
        write is: writable, one element named, within its range."""
        if len(args) != 2:
            raise CommandError(f"usage: {verb} NAME VALUE")
        it, elem = self.item(args[0])
        if not it.writable:
            raise CommandError(f"{it.name} {read_only} ({why_read_only(it)})")
        if it.count > 1 and elem is None:
            raise CommandError(f"{it.name} has {it.count} elements: {verb} {it.name}[i] VALUE")
        value = parse_value(it, args[1])
        if it.range and not it.range[0] <= value <= it.range[1]:
            raise CommandError(f"{it.name}: {args[1]} is outside its range "
                               f"{format_value(it, it.range[0])}..{format_value(it, it.range[1])}")
        return it, elem, value

    def cmd_write(self, args):
        it, elem, value = self._value_to_set(args, "write", "is read-only")
        with self.lock:
            try:
                how = self.c.write(it.id, it.type, value, elem or 0, what=it.name)
            except DebugError as err:
                raise CommandError(str(err)) from None
        name = f"{it.name}[{elem}]" if elem is not None else it.name
        when = "queued in the transaction" if self.in_tx else (
            "applied" if how == K.APPLIED else "applies at the next instant")
        self.emit(f"{name} := {format_value(it, value)} ({when})",
                  {"name": name, "value": value, "applied": how == K.APPLIED, "tx": self.in_tx})

    def cmd_tx(self, args):
        if len(args) != 1 or args[0] not in ("begin", "commit", "abort"):
            raise CommandError("usage: tx begin|commit|abort")
        with self.lock:
            if args[0] == "begin":
                self.c.tx_begin()
                self.in_tx, self.tx_reads = True, []
                self.emit("transaction open: reads and writes are queued until `tx commit`", {"tx": "open"})
            elif args[0] == "abort":
                self.in_tx, self.tx_reads = False, []
                self.c.tx_abort()
                self.emit("transaction aborted", {"tx": "aborted"})
            else:
                self.in_tx = False
                how, data = self.c.tx_commit()
                deadline = time.monotonic() + max(5.0, self.c.timeout)
                while how != K.APPLIED:
                    state, data = self.c.tx_result()
                    if state == 3:
                        break
                    if time.monotonic() > deadline:
                        raise CommandError("transaction committed, not yet applied (the program is halted "
                                           "inside an activation: `run` or `step` to the next instant)")
                    time.sleep(0.005)
                f = self.c.flags()
        at = 0
        values = []
        for it, elem in self.tx_reads:
            size = type_size(it.type)
            vals = [decode_value(it.type, data[at + k * size:at + (k + 1) * size]) for k in range(it.count)]
            at += size * it.count
            values.append((it, elem, vals[elem] if elem is not None else (vals if it.count > 1 else vals[0])))
        self.tx_reads = []
        if args[0] == "commit":
            self.emit(f"transaction applied (tick {f.tick})", {"tx": "applied", "tick": f.tick})
            for it, elem, v in values:
                name = f"{it.name}[{elem}]" if elem is not None else it.name
                self.emit(f"{name} = {format_value(it, v)}", {"name": name, "value": v})

    def cmd_stack(self, args):
        with self.lock:
            s = self.c.stack()
        m = self.map
        task = m.task_name(s.task) if m else s.task
        actor = m.actor_name(s.actor) if m else s.actor
        charts = []
        for cid, slots in enumerate(s.charts):
            name = m.charts[cid]["name"] if m and cid < len(m.charts) else f"chart {cid}"
            steps = [m.step_name(cid, x) if m else str(x) for x in slots if x is not None]
            charts.append({"chart": name, "active": steps})
        obj = {"tick": s.tick, "halted": s.halted, "why": s.why or None,
               "at": self.where(s.location, s.breakpoint, s.tick) if s.halted else None, "task": task,
               "actor": actor, "charts": charts}
        lines = [f"{self.when(s.tick)}: " + (f"halted ({s.why}) at {obj['at']}" if s.halted else "running"),
                 f"task        {task if task is not None else '-'}"]
        if s.halted and s.location.kind == K.P_ACTOR:
            lines.append(f"actor       {actor} (about to fire)")
        for ch in charts:
            lines.append(f"chart       {ch['chart']}: {' + '.join(ch['active']) or '(not started)'}")
        self.emit("\n".join(lines), obj)

    def _wait_halted(self, timeout: float):
        deadline = time.monotonic() + timeout
        while True:
            with self.lock:
                f = self.c.flags()
            if f.halted or time.monotonic() > deadline:
                return f
            time.sleep(0.01)

    def _report_halt(self, f, verb: str):
        if f.halted:
            text, obj = self.halt_text(f), self.halt_obj(f)
            if f.location.kind == K.P_CHART_END:  # `step chart`: the steps the evolution left the chart in
                with self.lock:
                    s = self.c.stack()
                slots = s.charts[f.location.a] if f.location.a < len(s.charts) else []
                steps = [self.map.step_name(f.location.a, x) if self.map else str(x) for x in slots if x is not None]
                name = self.map.charts[f.location.a]["name"] if self.map else f"chart {f.location.a}"
                text += f": {name} in {' + '.join(steps) or '(no step)'}"
                obj["active"] = steps
            self.emit(text, obj)
        else:
            self.emit(f"{verb}: not halted yet (tick {f.tick}); `wait` or `stack` later",
                      {"halted": False, "tick": f.tick})

    def cmd_run(self, args):
        with self.lock:
            self.c.run()
        self.emit("running", {"running": True})

    def cmd_break(self, args):
        if args and args[0] == "when":
            self._break_when(args[1:])
            return
        if args and args[0] == "at":
            if len(args) < 2:
                raise CommandError("usage: break at ITEM (a step Chart.Step, a transition Chart:A->B, "
                                   "an actor Dataflow.inst, a task, chart:NAME)")
            if self.map is None:
                raise CommandError("breakpoints are set by name: give --map")
            try:
                p = self.map.point(" ".join(args[1:]))
            except MapError as err:
                raise CommandError(str(err)) from None
            with self.lock:
                slot = self.c.bp_set(p.kind, p.a, p.b)
            self.emit(f"breakpoint {slot} at {self.map.describe(p.kind, p.a, p.b)}",
                      {"breakpoint": slot, "at": self.map.describe(p.kind, p.a, p.b)})
            return
        if args:
            raise CommandError("usage: break | break at ITEM")
        with self.lock:
            self.c.halt()
        self._report_halt(self._wait_halted(max(2.0, self.c.timeout)), "break")

    def _break_when(self, args):
        """``break when ITEM OP VALUE``: a conditional breakpoint."""
        if len(args) == 1:  # written without spaces: x>=3
            m = re.fullmatch(r"(.+?)(==|!=|<=|>=|<|>)(.+)", args[0])
            args = list(m.groups()) if m else args
        if len(args) != 3 or args[1] not in OPS:
            raise CommandError("usage: break when ITEM OP VALUE (OP: == != < <= > >=)")
        self._needs_slots("cond_slots", "conditional breakpoints", "conditions")
        it, elem = self.item(args[0])
        if it.count > 1 and elem is None:
            raise CommandError(f"{it.name} has {it.count} elements: break when {it.name}[i] {args[1]} VALUE")
        value = self.step_value(it, args[2]) if it.labels is not None else parse_value(it, args[2])
        with self.lock:
            try:
                slot = self.c.bp_when(it.id, it.type, args[1], value, elem or 0)
            except DebugError as err:
                raise CommandError(str(err)) from None
        name = f"{it.name}[{elem}]" if elem is not None else it.name
        self.emit(f"breakpoint {slot} when {name} {args[1]} {format_value(it, value)}",
                  {"breakpoint": slot, "when": f"{name} {args[1]} {format_value(it, value)}"})

    @staticmethod
    def step_value(it: Item, text: str) -> int:
        """A chart's step by name (or its id) as the value of Chart.active;
        a transition by name (`A->B`, spaces optional) as that of Chart.fired."""
        by_name = {name.replace(" ", ""): ident for ident, name in it.labels.items() if name is not None}
        key = text.replace(" ", "")
        if key in by_name:
            return by_name[key]
        if text.isdigit():
            return int(text)
        what = "transition" if it.kind == "fired" else "step"
        raise CommandError(f"{it.name}: no {what} '{text}' (its {what}s: {', '.join(sorted(by_name))})")

    def _needs_slots(self, field: str, what: str, setting: str) -> None:
        """Refuse a command the firmware was built without (HELLO: 0 slots)."""
        with self.lock:
            hello = self.c.hello_info or self.c.hello()
        if getattr(hello, field) == 0:
            raise CommandError(no_slots(what, setting))

    def cmd_force(self, args):
        if len(args) == 2:
            self._needs_slots("force_slots", "forcing", "force")
        it, elem, value = self._value_to_set(args, "force", "cannot be forced: it is read-only")
        with self.lock:
            try:
                how = self.c.force(it.id, it.type, value, elem or 0, what=it.name)
            except DebugError as err:
                raise CommandError(str(err)) from None
        name = f"{it.name}[{elem}]" if elem is not None else it.name
        self.emit(f"{name} forced to {format_value(it, value)} "
                  f"({'from now' if how == K.APPLIED else 'from the next instant'}, every instant until released)",
                  {"name": name, "forced": value, "applied": how == K.APPLIED})

    def cmd_release(self, args):
        if len(args) != 1:
            raise CommandError("usage: release NAME|all")
        self._needs_slots("force_slots", "forcing", "force")
        if args[0] == "all":
            with self.lock:
                self.c.release()
            self.emit("released every forced item", {"released": "all"})
            return
        it, elem = self.item(args[0])
        name = f"{it.name}[{elem}]" if elem is not None else it.name
        with self.lock:
            try:
                self.c.release(it.id, elem or 0)
            except DebugError as err:
                raise CommandError(f"{name} is not forced" if err.status == K.E_ID else str(err)) from None
        self.emit(f"released {name}", {"released": name})

    def cmd_forced(self, args):
        if args:
            raise CommandError("usage: forced")
        self._needs_slots("force_slots", "forcing", "force")
        with self.lock:
            found = self.c.forced()
        if not found:
            self.emit("nothing forced", None)
        for f in found:
            it = self._item_named(f.item)
            name = self._forced_name(f)
            value = decode_value(it.type, f.value)
            self.emit(f"{name} = {format_value(it, value)} (forced)", {"name": name, "forced": value})

    def cmd_step(self, args):
        unit = args[0] if args else "task"
        if len(args) > 1 or unit not in STEP_UNITS:
            raise CommandError("usage: step [task|chart|actor|instant]")
        with self.lock:
            try:
                self.c.step(unit)
            except DebugError as err:
                raise CommandError(str(err)) from None
        self._report_halt(self._wait_halted(5.0), "step")

    def cmd_reset(self, args):
        if args not in ([], ["--halt"]):
            raise CommandError("usage: reset [--halt]")
        halt = bool(args)
        with self.lock:
            self.c.reset(halt)
            deadline = time.monotonic() + 5.0
            while True:  # the firmware restarts: wait until it answers again
                time.sleep(0.05)
                try:
                    h = self.c.hello()
                    break
                except TransportError:
                    if time.monotonic() > deadline:
                        raise
            if self.map and h.program_id != self.map.program_id:
                raise CommandError(f"after the reset the firmware is program 0x{h.program_id:08x}, not the map's")
            f = self.c.flags()
        self.in_tx = False
        self.emit("reset: the program restarted" + (" (halted at its first instant)" if f.halted else ""),
                  {"reset": True, "halted": f.halted, "tick": f.tick})

    def cmd_load(self, args):
        if len(args) != 1:
            raise CommandError("usage: load FILE")
        try:
            text = Path(args[0]).read_bytes()
        except OSError as err:
            raise CommandError(f"{args[0]}: {err.strerror or err}") from None
        with self.lock:
            try:
                status = self.c.replace_model(text)
            except DebugError as err:
                if err.status == K.E_UNKNOWN_CMD:
                    raise CommandError("this target cannot replace its model (firmware: build and flash it; "
                                       "local execution with `easylab run` can)") from None
                raise CommandError(str(err)) from None
        if status.state == "refused":
            raise CommandError(f"refused, the program runs on: {status.message}")
        with self.lock:
            self.c.hello()  # the new program's sizes and id
        note = ""
        if self.map is not None:  # `easylab run --maps` rewrote the map in place
            try:
                fresh = DebugMap.load(self.map.path)
            except MapError:
                fresh = None
            if fresh is not None and fresh.program_id == status.program_id:
                self.map = fresh
            else:
                note = f"; the map {self.map.path} is not the new program's: give its map with --map"
        self.emit(f"replaced: program 0x{status.program_id:08x} runs"
                  + (f" ({status.message})" if status.message else "") + note,
                  {"replaced": True, "program_id": f"0x{status.program_id:08x}"})

    def cmd_delete(self, args):
        if len(args) != 1 or not (args[0] == "all" or args[0].isdigit()):
            raise CommandError("usage: delete N|all")
        with self.lock:
            try:
                self.c.bp_clear(None if args[0] == "all" else int(args[0]))
            except DebugError as err:
                raise CommandError(f"no breakpoint {args[0]}" if err.status == K.E_ID else str(err)) from None
        self.emit(f"deleted breakpoint {args[0]}" if args[0] != "all" else "deleted every breakpoint",
                  {"deleted": args[0]})

    def cmd_breakpoints(self, args):
        if args == ["--all"]:
            if self.map is None:
                raise CommandError("give --map to list the places")
            for p in self.map.points():
                self.emit(p.label, {"point": p.label, "kind": p.kind, "a": p.a, "b": p.b})
            return
        with self.lock:
            bps = self.c.bp_list()
        if not bps:
            self.emit("no breakpoints", None)
        for b in bps:
            if b.kind == K.P_CONDITION:
                at = self.describe_condition(b)
            else:
                at = self.map.describe(b.kind, b.a, b.b) if self.map else f"{b.kind} {b.a}.{b.b}"
            self.emit(f"{b.slot}: {at} (hit {b.hits} time{'s' if b.hits != 1 else ''})",
                      {"breakpoint": b.slot, "at": at, "hits": b.hits})

    def cmd_wait(self, args):
        timeout = parse_duration(args[0]) if args else 10.0
        f = self._wait_halted(timeout)
        self._report_halt(f, "wait")
        if not f.halted:
            raise CommandError(f"the program did not halt within {timeout:g} s")

    def cmd_counters(self, args):
        with self.lock:
            counters = self.c.counters()
        self.emit("  ".join(f"{k} {v}" for k, v in counters.items()), counters)

    def cmd_sleep(self, args):
        if len(args) != 1:
            raise CommandError("usage: sleep DURATION")
        time.sleep(parse_duration(args[0]))

    def cmd_watch(self, args):
        names, every, count = [], 0.1, None
        i = 0
        while i < len(args):
            if args[i] == "--every" and i + 1 < len(args):
                every = parse_duration(args[i + 1])
                i += 2
            elif args[i] == "--count" and i + 1 < len(args) and args[i + 1].isdigit():
                count = int(args[i + 1])
                i += 2
            else:
                names.append(args[i])
                i += 1
        if not names:
            raise CommandError("usage: watch NAME... [--every 100ms] [--count N]")
        targets = [self.item(n) for n in names]
        labels = [f"{it.name}[{e}]" if e is not None else it.name for it, e in targets]
        live = self.interactive and not self.json and self.out.isatty()
        if count is None and not live:
            count = 10
        width = max(12, *(len(x) for x in labels))
        n = 0
        try:
            while count is None or n < count:
                with self.lock:
                    f = self.c.flags()
                    values = self._read_values(targets)
                n += 1
                if self.json:
                    self.emit("", {"tick": f.tick, "values": dict(zip(labels, (step_names(it, v) for (it, _), v
                                                                              in zip(targets, values))))})
                elif live:
                    rows = [f"{'tick':<{width}}  {f.tick}" + (f" ({self.map.ms(f.tick)} ms)" if self.map else "")
                            + ("   (halted)" if f.halted else "")]
                    rows += [f"{lab:<{width}}  {format_value(it, v)}" for lab, (it, _), v in
                             zip(labels, targets, values)]
                    if n > 1:
                        self.out.write(f"\x1b[{len(rows)}F")
                    self.out.write("".join(f"{r}\x1b[K\n" for r in rows))
                    self.out.flush()
                else:
                    self.emit(f"{self.when(f.tick)}: " + "  ".join(f"{lab} = {format_value(it, v)}" for lab, (it, _), v
                                                            in zip(labels, targets, values)), None)
                if count is None or n < count:
                    time.sleep(every)
        except KeyboardInterrupt:
            if live:
                self.out.write("(watch ended)\n")

    # -------------------------------------------------------------- dispatch

    def execute(self, line: str) -> None:
        try:
            words = shlex.split(line, comments=True)
        except ValueError as err:
            raise CommandError(f"cannot read the command: {err}") from None
        if not words:
            return
        name, args = words[0], words[1:]
        if name in ("quit", "exit"):
            raise SystemExit(EXIT_OK)
        if name == "help":
            self.emit("\n".join(COMMANDS.values()), None)
            return
        fn = getattr(self, f"cmd_{name}", None)
        if fn is None:
            close = [c for c in COMMANDS if c.startswith(name)]
            raise CommandError(f"unknown command '{name}'" + (f" (did you mean {', '.join(close)}?)" if close
                                                               else " (`help` lists them)"))
        try:
            fn(args)
        except DebugError as err:
            raise CommandError(str(err)) from None


def why_read_only(it: Item) -> str:
    """Why an item cannot be written or forced (one phrase)."""
    if it.kind == "dev_in":
        return "a device `in` datum: the application writes it at every publication"
    if it.kind == "dev_state":
        return "a device's state: only its handlers change it"
    if it.kind in ("chart", "step_time", "fired"):
        return "a chart's state: only its evolutions change it"
    return "the firmware does not let the debugger write it"


# ====================================================================== interactive


class Console(cmd.Cmd):
    """The interactive console: readline editing, history, completion."""

    prompt = "(easylab) "

    def __init__(self, session: Session):
        super().__init__()
        self.s = session
        self.intro = (f"easylab-debug: {session.url}, model {session.map.model if session.map else '?'} "
                      f"(program 0x{session.c.hello_info.program_id:08x}). `help` lists the commands.")
        self._stop = threading.Event()
        self._known_halt = None  # the halt the person has seen: (tick, kind, a, b)
        self._watcher = threading.Thread(target=self._watch_halts, daemon=True)

    def preloop(self):
        try:
            import readline
            readline.set_completer_delims(" \t\n;")
            hist = os.path.expanduser("~/.easylab_debug_history")
            try:
                readline.read_history_file(hist)
            except OSError:
                pass
            readline.set_history_length(1000)
            import atexit
            atexit.register(lambda: _save_history(readline, hist))
        except ImportError:
            pass
        if not self._watcher.is_alive():
            self._watcher.start()

    def postloop(self):
        pass

    def _watch_halts(self):
        """Tell the person when the running program halts (a breakpoint)."""
        while not self._stop.wait(0.25):
            try:
                with self.s.lock:
                    f = self.s.c.flags()
            except (TransportError, DebugError):
                continue
            key = (f.tick, f.location.kind, f.location.a, f.location.b) if f.halted else None
            if key is not None and key != self._known_halt:
                msg = f"\n[{self.s.halt_text(f)}]\n"
                try:
                    import readline
                    msg += self.prompt + readline.get_line_buffer()
                except ImportError:
                    pass
                sys.stdout.write(msg)
                sys.stdout.flush()
            self._known_halt = key

    def onecmd(self, line):
        line = line.strip()
        if line == "EOF":
            print()
            return True
        try:
            self.s.execute(line)
        except CommandError as err:
            print(f"error: {err}")
        except KeyboardInterrupt:
            print()
        if line.split()[:1] in (["break"], ["step"], ["wait"], ["reset"], ["stack"], ["info"]):
            with self.s.lock:  # these commands show the halt themselves
                try:
                    f = self.s.c.flags()
                    self._known_halt = (f.tick, f.location.kind, f.location.a, f.location.b) if f.halted else None
                except (TransportError, DebugError):
                    pass
        return False

    def emptyline(self):
        return False

    def completenames(self, text, *ignored):
        return [c + " " for c in list(COMMANDS) + ["help", "exit"] if c.startswith(text)]

    def completedefault(self, text, line, begidx, endidx):
        words = line[:begidx].split()
        if not words:
            return []
        cmdname = words[0]
        m = self.s.map
        if cmdname in ("read", "write", "watch", "vars", "force", "release") and m is not None:
            if cmdname in ("write", "force", "release") and len(words) > 1:
                return []
            names = [i.name for i in m.items if cmdname not in ("force", "release") or i.writable]
            return [n + " " for n in names + (["all"] if cmdname == "release" else []) if n.startswith(text)]
        if cmdname == "step":
            return [u + " " for u in STEP_UNITS if u.startswith(text)]
        if cmdname == "tx":
            return [u + " " for u in ("begin", "commit", "abort") if u.startswith(text)]
        if cmdname == "break":
            if len(words) == 1:
                return [w + " " for w in ("at", "when") if w.startswith(text)]
            if words[1] == "when":  # break when ITEM OP VALUE
                if len(words) == 2 and m is not None:
                    return [i.name + " " for i in m.items if i.name.startswith(text)]
                return [op + " " for op in OPS if op.startswith(text)] if len(words) == 3 else []
            if m is not None:
                return [p.label + " " for p in m.points() if p.label.startswith(text)]
        if cmdname == "reset":
            return ["--halt "] if "--halt".startswith(text) else []
        if cmdname == "breakpoints":
            return ["--all "] if "--all".startswith(text) else []
        return []


def _save_history(readline, path):
    try:
        readline.write_history_file(path)
    except OSError:
        pass


# ====================================================================== main


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog=PROG, description="The EasyLab debug console: read, write, watch, break and step a running firmware.",
        epilog="Commands:\n  " + "\n  ".join(COMMANDS.values()), formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("url", metavar="URL", help="serial device, pty (link) or socket://HOST:PORT")
    p.add_argument("--map", metavar="FILE", help="debug_map.json of the build running on the target")
    p.add_argument("-c", dest="commands", metavar="CMDS", help='commands separated by ";", then exit')
    p.add_argument("--script", metavar="FILE", help="commands from FILE (one a line, # comments), then exit")
    p.add_argument("--json", action="store_true", help="output one JSON object per line")
    p.add_argument("--timeout", type=float, default=1.0, metavar="S", help="answer timeout in seconds (default 1)")
    p.add_argument("--baud", type=int, default=115200, help="baud rate of a serial device (default 115200)")
    return p


def _fail(msg: str, status: int = EXIT_FAIL) -> int:
    print(f"{PROG}: error: {msg}", file=sys.stderr)
    return status


def connect(url: str, map_path: str | None, timeout: float = 1.0, baud: int = 115200):
    """(client, map) after the identity check; raises TransportError or
    MapError or SystemExit-worthy _Mismatch."""
    dmap = DebugMap.load(map_path) if map_path else None
    client = DebugClient.open(url, timeout, baud)
    try:
        h = client.hello()
    except TransportError:
        client.close()
        raise
    if dmap is not None and h.program_id != dmap.program_id:
        client.close()
        raise Mismatch(f"{url} runs program 0x{h.program_id:08x}, but {dmap.path} is the debug map of model "
                       f"{dmap.model}, program 0x{dmap.program_id:08x}: use the debug_map.json written by the "
                       f"build of the firmware that runs there, or run/flash the build of {dmap.model} "
                       f"that wrote this map")
    return client, dmap


class Mismatch(Exception):
    pass


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["web"]:  # the online mode (docs/online.md)
        from .debug_web.server import main as web_main
        return web_main(argv[1:])
    args = build_parser().parse_args(argv)
    try:
        client, dmap = connect(args.url, args.map, args.timeout, args.baud)
    except MapError as err:
        return _fail(str(err), EXIT_USAGE)
    except Mismatch as err:
        return _fail(str(err), EXIT_USAGE)
    except ProtocolError as err:
        return _fail(str(err), EXIT_USAGE)
    except TransportError as err:
        text = str(err)
        if "no answer" in text:
            text += " (is the firmware running, with its debug interface on that port?)"
        return _fail(text)
    lines: list[str] | None = None
    if args.commands is not None:
        lines = [c for c in args.commands.split(";")]
    elif args.script is not None:
        try:
            with open(args.script, encoding="utf-8") as f:
                lines = f.read().splitlines()
        except OSError as err:
            return _fail(f"{args.script}: {err.strerror or err}", EXIT_USAGE)
    session = Session(client, dmap, args.url, args.json, interactive=lines is None)
    try:
        if lines is not None:
            for number, line in enumerate(lines, 1):
                try:
                    session.execute(line)
                except CommandError as err:
                    where = f"{args.script}:{number}: " if args.script else ""
                    return _fail(f"{where}{line.strip()}: {err}")
            return EXIT_OK
        console = Console(session)
        try:
            while True:
                try:
                    console.cmdloop()
                    return EXIT_OK
                except KeyboardInterrupt:
                    print("^C")
                    console.intro = None
        finally:
            console._stop.set()
    except SystemExit as done:
        return int(done.code or 0)
    except TransportError as err:
        return _fail(str(err))
    finally:
        client.close()


if __name__ == "__main__":
    sys.exit(main())
