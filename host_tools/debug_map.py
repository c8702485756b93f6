"""The debug map (debug_map.json, written by ``easylab build`` beside a debug
firmware): names, types and locations for the ids of the debug protocol.

Without a map the tools still work by id (``#3``), asking the firmware for
each item's type (ITEM_INFO).
"""

from __future__ import annotations

import fnmatch
import re
from dataclasses import dataclass
from pathlib import Path

from .debug_protocol import K, PROBE_NAMES
from .map_schema import DEBUG_MAP_SCHEMA, MapFileError, read_map
from .units import Scale

MAP_FORMAT = "easylab-debug-map"


class MapError(Exception):
    """A map that cannot be read, or a name it does not know (one line)."""


@dataclass
class Item:
    id: int
    name: str
    kind: str
    type: str
    count: int
    flags: list
    unit: str | None = None
    range: list | None = None
    location: str = "?"
    chart: int | None = None  # a chart's state (kinds chart, step_time, fired): its chart
    step: int | None = None  # a step's time: its step
    # a chart's active steps: step id -> name; the transition it fired last: transition id -> name `A -> B`
    # (its type's all ones, NONE8 or NONE16: none)
    labels: dict | None = None
    scale: Scale = Scale()  # stored integer x scale = the engineering value (host_tools/units.py)

    @property
    def writable(self) -> bool:
        return "write" in self.flags


@dataclass
class Point:
    """A probe point: where a breakpoint can be set."""

    kind: int
    a: int
    b: int
    label: str


class DebugMap:
    def __init__(self, data: dict, path: str = "?"):
        if data.get("format") != MAP_FORMAT:
            raise MapError(f"{path}: not an EasyLab debug map")
        self.path = path
        self.data = data
        self.model = data.get("model", "?")
        self.program_id = int(str(data["program_id"]), 0)
        self.tick_us = int(data.get("tick_us", 0))
        self.charts = data.get("charts", [])
        self.actors = data.get("actors", [])
        self.tasks = data.get("tasks", [])
        self.items = [Item(i["id"], i["name"], i["kind"], i["type"], i["count"], i["flags"], i.get("unit"),
                           i.get("range"), i.get("location", "?"), i.get("chart"), i.get("step"),
                           self._labels(i),
                           Scale.of(i.get("scale")))
                      for i in data["items"]]
        self.by_name = {i.name: i for i in self.items}
        self.by_id = {i.id: i for i in self.items}
        # A chart's name alone names its active steps (`watch Cylinder`).
        self.aliases = {i.name[:-len(".active")]: i for i in self.items if i.kind == "chart"}

    def _labels(self, item: dict) -> dict | None:
        """The names of the values of a chart's `active` (its steps) or
        `fired` item (its transitions); None for any other item."""
        if item["kind"] not in ("chart", "fired"):
            return None
        c = self._chart(item["chart"]) or {"steps": [], "transitions": []}
        if item["kind"] == "chart":
            return {**{s["id"]: s["name"] for s in c["steps"]}, K.NONE8: None}
        none = K.NONE8 if item["type"] == "uint8" else K.NONE16
        return {**{t["id"]: t["name"] for t in c.get("transitions", [])}, none: None}

    @classmethod
    def load(cls, path: str | Path) -> "DebugMap":
        """The debug map in the file at ``path``, valid against
        map_schema.DEBUG_MAP_SCHEMA; otherwise :class:`MapError` in one line."""
        try:
            data = read_map(path, DEBUG_MAP_SCHEMA, "debug map")
        except MapFileError as err:
            raise MapError(str(err)) from None
        return cls(data, str(path))

    # -------------------------------------------------------------- items

    def item(self, name: str) -> Item:
        if name in self.by_name:
            return self.by_name[name]
        if name in self.aliases:
            return self.aliases[name]
        m = re.fullmatch(r"#(\d+)", name)
        if m and int(m.group(1)) in self.by_id:
            return self.by_id[int(m.group(1))]
        close = [n for n in self.by_name if n.lower() == name.lower() or n.endswith("." + name)]
        hint = f" (did you mean {', '.join(close[:3])}?)" if close else " (`vars` lists them)"
        raise MapError(f"no item '{name}' in model {self.model}{hint}")

    def glob(self, pattern: str | None) -> list[Item]:
        if not pattern:
            return list(self.items)
        return [i for i in self.items if fnmatch.fnmatchcase(i.name, pattern)]

    # -------------------------------------------------------------- probe points

    def points(self) -> list[Point]:
        """Every place a breakpoint can go, with its name in the console."""
        pts = [Point(K.P_INSTANT, 0, 0, "instant")]
        pts += [Point(K.P_TASK, t["id"], 0, f"task:{t['name']}") for t in self.tasks]
        for c in self.charts:
            pts.append(Point(K.P_CHART, c["id"], 0, f"chart:{c['name']}"))
            pts += [Point(K.P_STEP, c["id"], s["id"], f"{c['name']}.{s['name']}") for s in c["steps"]]
            pts += [Point(K.P_TRANSITION, c["id"], t["id"], f"{c['name']}:{t['name'].replace(' ', '')}")
                    for t in c["transitions"]]
        pts += [Point(K.P_ACTOR, a["id"], 0, f"actor:{a['name']}") for a in self.actors]
        return pts

    def point(self, text: str) -> Point:
        """A probe point by name: ``Chart.Step``, ``Chart:A->B``,
        ``actor:Dataflow.inst`` or ``Dataflow.inst``, ``task:NAME`` or NAME,
        ``chart:NAME``, ``instant``."""
        key = text.replace(" ", "")
        pts = self.points()
        exact = [p for p in pts if p.label == key]
        if exact:
            return exact[0]
        loose = [p for p in pts if p.label.split(":", 1)[-1] == key] if ":" not in key or "->" in key else []
        if len(loose) == 1:
            return loose[0]
        if len(loose) > 1:
            raise MapError(f"'{text}' is ambiguous: {', '.join(p.label for p in loose)}")
        raise MapError(f"no step, transition, actor, chart or task '{text}' in model {self.model} "
                       f"(`breakpoints --all` lists them)")

    def describe(self, kind: int, a: int, b: int) -> str:
        """The name of a probe point (for halts and breakpoint lists)."""
        if kind == K.P_CHART_END:  # where `step chart` halts: no breakpoint goes there
            c = self._chart(a)
            return f"the end of chart:{c['name']}'s evolution" if c else f"the end of chart {a}'s evolution"
        if kind == K.P_CONDITION:  # a conditional breakpoint's item (its comparison: the breakpoint list)
            it = self.by_id.get(a)
            name = it.name if it is not None else f"#{a}"
            return f"condition on {name}" + (f"[{b}]" if it is not None and it.count > 1 else "")
        for p in self.points():
            if (p.kind, p.a, p.b) == (kind, a, b):
                return p.label if p.kind != K.P_STEP else f"step {p.label}"
        return f"{PROBE_NAMES.get(kind, kind)} {a}.{b}"

    def _chart(self, chart: int) -> dict | None:
        return next((c for c in self.charts if c["id"] == chart), None)

    def location(self, kind: int, a: int, b: int) -> str | None:
        """``file:line`` of the element of a probe point in the model (the
        chart of a chart's evolution, the step, the transition, the actor,
        the task), or None (an instant: see :meth:`released`)."""
        if kind == K.P_TASK:
            found = next((t for t in self.tasks if t["id"] == a), None)
        elif kind == K.P_ACTOR:
            found = next((x for x in self.actors if x["id"] == a), None)
        elif kind in (K.P_CHART, K.P_CHART_END, K.P_STEP, K.P_TRANSITION):
            found = self._chart(a)
            if found is not None and kind != K.P_CHART and kind != K.P_CHART_END:
                key = "steps" if kind == K.P_STEP else "transitions"
                found = next((x for x in found[key] if x["id"] == b), None)
        elif kind == K.P_CONDITION:  # the item's declaration
            it = self.by_id.get(a)
            return it.location if it is not None and it.location != "?" else None
        else:
            found = None
        return found.get("location") if found is not None else None

    def released(self, tick: int) -> list[dict]:
        """The tasks released at a tick (an instant's: its offset reached,
        then every period), with their ``location``."""
        out = []
        for t in self.tasks:
            period, offset = t.get("period_us", 0), t.get("offset_us", 0)
            at = tick * self.tick_us
            if period and at >= offset and (at - offset) % period == 0:
                out.append(t)
        return out

    def ms(self, tick: int) -> str:
        """A tick as logical time in milliseconds (``25``, ``0.5``)."""
        us = tick * self.tick_us
        return str(us // 1000) if us % 1000 == 0 else f"{us / 1000:.3f}".rstrip("0")

    def task_name(self, task: int | None) -> str | None:
        if task is None:
            return None
        return next((t["name"] for t in self.tasks if t["id"] == task), f"task {task}")

    def actor_name(self, actor: int | None) -> str | None:
        if actor is None:
            return None
        return next((a["name"] for a in self.actors if a["id"] == actor), f"actor {actor}")

    def step_name(self, chart: int, step: int | None) -> str | None:
        if step is None:
            return None
        c = next((c for c in self.charts if c["id"] == chart), None)
        if c is None:
            return str(step)
        return next((s["name"] for s in c["steps"] if s["id"] == step), str(step))
