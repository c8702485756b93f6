"""Program-wide rules: tasks, what runs once, single writers, connected
channels, interfaces and resource claims (docs/language.md)."""

from __future__ import annotations

from fractions import Fraction

from ...core.source import Span, note
from ...core import types as T
from .. import ast
from ..model import ChartInfo, Claim, InterfaceInfo, TaskInfo
from ...core.debug_protocol import protocol_constants
from .base import show_value, claim_owner, whole_us


class TaskRules:
    # ================================================================ tasks

    def check_task(self, decl: ast.Task) -> None:
        attrs: dict[str, object] = {}
        typer = self.const_typer()
        for a in decl.attrs:
            if a.key in attrs:
                self.error(a.span, f"'{a.key}' is given twice for task '{decl.name}'")
                continue
            v = typer.expect_const(a.value, T.TIME, f"the {a.key} of task '{decl.name}'")
            attrs[a.key] = (v.const, a.span) if v.type is not None else None
        if "period" not in attrs:
            self.error(decl.name_span, f"task '{decl.name}' has no period", "write: task name period 10 ms { ... }")
            return
        if any(v is None for v in attrs.values()):
            return
        period, pspan = attrs["period"]
        offset, ospan = attrs.get("offset", (Fraction(0), None))
        deadline, dspan = attrs.get("deadline", (period, None))
        wcet, wspan = attrs.get("wcet", (None, None))
        bad = False
        if period <= 0:
            self.error(pspan, "a task's period must be positive")
            bad = True
        elif not whole_us(period):
            self.error(pspan, "a task's period is a whole number of microseconds")
            bad = True
        if not bad and not 0 <= offset < period:
            self.error(ospan, f"the offset must be below the period ({show_value(period, T.TIME)})")
            bad = True
        if not bad and not 0 < deadline <= period:
            self.error(dspan, f"the deadline must be positive and at most the period ({show_value(period, T.TIME)})")
            bad = True
        if not bad and wcet is not None and not 0 < wcet <= deadline:
            self.error(wspan, f"the wcet must be positive and at most the deadline ({show_value(deadline, T.TIME)})")
            bad = True
        runs = []
        for r in decl.runs:
            target = self.lookup(r.name, r.name_span, (ast.Dataflow, ast.Chart), "dataflow or chart")
            if target is None:
                continue
            runs.append(self.dataflows.get(r.name) or self.charts.get(r.name))
        if bad:
            return
        info = TaskInfo(decl, period, offset, deadline, wcet, [r for r in runs if r is not None])
        self.tasks[decl.name] = info

    def check_run_once(self) -> None:
        """Nothing is run by two tasks (directly or through a chart)."""
        owner: dict[str, tuple[TaskInfo, Span]] = {}

        def claim(item, task: TaskInfo, span: Span) -> None:
            first = owner.get(item.name)
            if first is not None and first[0] is not task:
                self.error(span, f"{'chart' if isinstance(item, ChartInfo) else 'dataflow'} '{item.name}' is run "
                                 f"by task '{first[0].name}' and by task '{task.name}'",
                           "a dataflow or chart runs in one task; split it, or use a channel between tasks",
                           [note(first[1], f"run by task '{first[0].name}' here")])
                return
            owner.setdefault(item.name, (task, span))
            item.task = task

        for task in self.tasks.values():
            for r, run in zip(task.runs, [r for r in task.decl.runs if r.name in self.dataflows or r.name in self.charts]):
                claim(r, task, run.span)
                if isinstance(r, ChartInfo):
                    for step in r.steps.values():
                        for df, run_decl in zip(step.runs, step.decl.runs):
                            claim(df, task, run_decl.span)

    def check_writers(self) -> None:
        """One writer per var and device input: all writes come from one task."""
        targets = [(f"var '{d.name}'", d) for d in self.data.values() if d.kind == "var"]
        seen: set[int] = set()
        for name, datum in self.device_data.items():
            if datum.port.direction == "in" and id(datum) not in seen:
                seen.add(id(datum))
                targets.append((f"device input '{datum.name}'", datum))
        for label, target in targets:
            first = None
            for w in target.writers:
                task = w.owner.task
                if task is None:
                    continue
                if first is None:
                    first = (task, w)
                elif first[0] is not task:
                    self.error(w.span, f"{label} is written by task '{task.name}' and by task '{first[0].name}'",
                               "each var and device input has one writing task; pass data between tasks "
                               "through a channel",
                               [note(first[1].span, f"written in task '{first[0].name}' here")])
                    break

    def check_channels_connected(self) -> None:
        for ch in self.channels.values():
            if not ch.producers and "produced" not in ch.named_as:
                self.error(ch.decl.name_span, f"channel '{ch.name}' has no producer",
                           f"write to it from a dataflow: x.y -> {ch.name}")
            if not ch.consumers and "consumed" not in ch.named_as:
                self.error(ch.decl.name_span, f"channel '{ch.name}' has no consumer",
                           f"read it in a dataflow: {ch.name} -> x.in")
            for group, role in ((ch.producers, "produced"), (ch.consumers, "consumed")):
                for extra in group[1:]:
                    self.error(extra.decl.span, f"channel '{ch.name}' is {role} by more than one edge",
                               notes=[note(group[0].decl.span, "the first edge")])

    # ================================================================ interfaces and resources

    _INTERFACE_KEYS = {
        "debug": {"baud", "force", "conditions"},
        "modbus-rtu": {"baud", "parity", "unit"},
        "modbus-tcp": {"port", "unit"},
    }
    _DEFAULTS = {
        "debug": {"baud": 115200},
        "modbus-rtu": {"baud": 19200, "parity": "even", "unit": 1},
        "modbus-tcp": {"port": 502, "unit": 1},
    }

    # The debug interface's slots of forced elements and conditional
    # breakpoints: at most the protocol's (docs/protocol.md, "Forcing").
    _DEBUG_SLOTS = {"force": protocol_constants().FORCE_MAX, "conditions": protocol_constants().COND_MAX}

    def check_interface(self, iface: ast.Interface) -> None:
        kind = "debug" if iface.kind == "debug" else f"modbus-{iface.mode}"
        for other in self.interfaces:
            if other.kind == kind:
                self.error(iface.span, f"a model has at most one {kind.replace('-', ' ')} interface",
                           notes=[note(other.decl.span, "the other one")])
                return
        settings = dict(self._DEFAULTS[kind])
        given: set[str] = set()
        for a in iface.attrs:
            if a.key not in self._INTERFACE_KEYS[kind]:
                self.error(a.span, f"'{a.key}' is not a setting of the {kind.replace('-', ' ')} interface",
                           f"its settings: {', '.join(sorted(self._INTERFACE_KEYS[kind]))}")
                continue
            if a.key in given:
                self.error(a.span, f"'{a.key}' is given twice")
                continue
            given.add(a.key)
            value = a.value
            if a.key == "parity":
                if value not in ("none", "even", "odd"):
                    self.error(a.value_span, f"parity must be none, even or odd, not '{value}'")
                    continue
            elif not isinstance(value, int):
                self.error(a.value_span, f"'{a.key}' takes a number, not '{value}'")
                continue
            elif a.key == "baud" and not 300 <= value <= 4_000_000:
                self.error(a.value_span, f"baud rate {value} is outside 300..4000000")
                continue
            elif a.key == "unit" and not 1 <= value <= 247:
                self.error(a.value_span, f"Modbus unit id {value} is outside 1..247")
                continue
            elif a.key == "port" and not 1 <= value <= 65535:
                self.error(a.value_span, f"TCP port {value} is outside 1..65535")
                continue
            elif a.key in self._DEBUG_SLOTS and not 0 <= value <= self._DEBUG_SLOTS[a.key]:
                self.error(a.value_span, f"'{a.key}' takes 0..{self._DEBUG_SLOTS[a.key]} slots, not {value}")
                continue
            settings[a.key] = value
        claim = None
        if kind == "modbus-tcp":
            if iface.resource is not None:
                self.error(iface.resource.span, "Modbus TCP runs on the board's network, not 'on' a resource")
        elif iface.resource is None:
            self.error(iface.span, f"the {kind.replace('-', ' ')} interface needs a UART: 'on uart0'")
            return
        else:
            claim = self.eval_claim(iface.resource, self.const_typer(), kind.replace("-", " "))
            if claim is not None:
                if claim.kind != "uart":
                    self.error(iface.resource.span, f"the {kind.replace('-', ' ')} interface runs on a UART, "
                                                    f"not on '{claim}'")
                    return
                self.claims.append(claim)
        self.interfaces.append(InterfaceInfo(iface, kind, claim, settings))

    def check_claims(self) -> None:
        """One owner per resource; devices on a shared bus share it at
        distinct places (addresses, chip selects), and a bus owned whole is
        shared with nobody."""
        first: dict[tuple, Claim] = {}
        whole: dict[tuple, Claim] = {}  # resource -> its first claim without a place
        shared: dict[tuple, Claim] = {}  # resource -> its first claim at a place on it
        for c in self.claims:
            other = first.get(c.key)
            if other is None and c.select is None:
                other = shared.get(c.resource)
            elif other is None:
                other = whole.get(c.resource)
            if other is None:
                first[c.key] = c
                (whole if c.select is None else shared).setdefault(c.resource, c)
                continue
            if c.select is not None and c.key == other.key:
                place = {"addr": "address", "cs": "chip select"}.get(c.select[0], c.select[0])
                self.error(c.span, f"{c} is claimed by {claim_owner(c)} and by {claim_owner(other)}: the devices "
                                   f"on one bus need distinct places on it",
                           f"give one of them another {place}",
                           [note(other.span, f"claimed by {claim_owner(other)} here")])
                continue
            self.error(c.span, f"resource {c} is claimed by {claim_owner(c)} and by {claim_owner(other)}"
                       + (f" ({other})" if str(other) != str(c) else ""),
                       "each resource has one owner; choose another pin, channel or UART",
                       [note(other.span, f"claimed by {claim_owner(other)} here")])


# ==================================================================== helpers


