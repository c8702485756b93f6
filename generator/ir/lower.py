"""Lowering: a checked and analysed model -> the IR (docs/ir.md). The one
place where the front end's model meets the IR; everything after reads
the IR alone."""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

from ..analysis.timing import Timing
from ..core import expr as I
from ..core import types as T
from ..frontend.loader import module_dir
from ..frontend.model import ActorInstanceInfo, ChartInfo, CheckedModel, DataflowInfo
from .deployment import Crossing, Deployment, ExportSpec, LinkMember, LinkSpec, NodeSpec, topic_name
from .program import (Action, ActorInstance, ActorSpec, Buffer, Channel, Chart, Dataflow, Device, External, Fire,
                      Instant, Interface, Item, Port, Program, RemoteSettings, Schedule, Step, Task, Transition,
                      location, program_id)


def _runtime_value(t: T.ValueType, value):
    """A checked-model constant in run-time units."""
    if t is T.TIME:
        return int(Fraction(value) / 1000)
    if t is T.FLOAT32:
        return T.to_double(value)
    if t is T.BOOL:
        return bool(value)
    return int(value) if not isinstance(value, str) else value


class _Lowering:
    def __init__(self, model: CheckedModel, timing: Timing):
        self.m = model
        self.timing = timing
        self.items: list[Item] = []
        self.item_of: dict[int, int] = {}  # id(DataInfo | DeviceDatum) -> item id
        self.devices: list[Device] = []
        self.specs: list[ActorSpec] = []
        self.spec_keys: dict[str, int] = {}
        self.instances: list[ActorInstance] = []
        self.dataflows: list[Dataflow] = []
        self.df_index: dict[str, int] = {}
        self.charts: list[Chart] = []
        self.channels: list[Channel] = []
        self.channel_index: dict[str, int] = {}
        self.task_index = {t.name: i for i, t in enumerate(timing.tasks)}

    # -------------------------------------------------------------- items

    def lower_items(self) -> None:
        for kind in ("param", "var"):
            for d in self.m.data.values():
                if d.kind != kind:
                    continue
                self._add_item(d, Item(
                    len(self.items), d.name, kind, d.type, 1, _runtime_value(d.type, d.initial),
                    location(d.decl.name_span),
                    range=tuple(_runtime_value(d.type, v) for v in d.range) if d.range else None,
                    unit=d.decl.unit, service=d.decl.service.access if d.decl.service else None,
                    address=d.decl.service.address if d.decl.service else None, persist=d.decl.persist,
                    scale=T.decimal_text(d.decl.scale) if d.decl.scale is not None else None))
        seen: set[int] = set()
        for dev in self.m.devices:
            formal_types = {f.name: T.ALL_TYPES[f.type.name] for f in dev.type.params}
            device = Device(len(self.devices), dev.path, dev.driver, dev.type.name,
                            {k: v for k, v in dev.args.items()}, [], [str(c) for c in dev.claims],
                            location(dev.span), handlers=dict(dev.handlers),
                            params={k: (formal_types[k], _runtime_value(formal_types[k], v))
                                    for k, v in dev.args.items()},
                            states=list(dev.states),
                            array_ports=[p.name for p in dev.ports.values() if p.array], chip=dev.chip)
            self.devices.append(device)
            for port in dev.ports.values():
                datum = self.m.device_data[f"{dev.path}.{port.name}"]
                if id(datum) in seen:
                    continue
                seen.add(id(datum))
                # A device `in` datum starts at its safe value (docs/ir.md, "Items").
                initial = False if port.type is T.BOOL else (0.0 if port.type is T.FLOAT32 else 0)
                if datum.safe is not None:
                    initial = _runtime_value(port.type, datum.safe)
                item = Item(len(self.items), datum.name, "dev_out" if port.direction == "out" else "dev_in",
                            port.type, port.rate, initial, location(dev.span), device=device.id, port=port.name)
                self._add_item(datum, item)
                device.items.append(item.id)

    def _add_item(self, key, item: Item) -> None:
        self.item_of[id(key)] = item.id
        self.items.append(item)

    # -------------------------------------------------------------- actors

    def spec_for(self, inst: ActorInstanceInfo) -> int:
        atype = inst.actor_type
        const_args = {n: (a.type, _runtime_value(a.type, a.const) if not isinstance(a.const, str) else a.const)
                      for n, a in inst.args.items() if a.const is not None}
        runtime = {n: a.type for n, a in inst.args.items() if a.const is None}
        key = json.dumps([atype.name, {k: v.name for k, v in inst.type_bindings.items()},
                          {k: [t.name, repr(v)] for k, (t, v) in const_args.items()}, sorted(runtime)],
                         sort_keys=True)
        if key in self.spec_keys:
            return self.spec_keys[key]
        ports = [Port(p.name, p.direction, inst.port_types[p.name], inst.port_rates[p.name], p.rate is not None)
                 for p in atype.ports]
        states = [(s.name, *inst.state_types[s.name]) for s in atype.states]
        impl = None
        if atype.impl is not None:
            impl = str(module_dir(Path(self.m.actor_type_files[atype.name])) / atype.impl)
        same_type = sum(1 for s in self.specs if s.type_name == atype.name)
        spec = ActorSpec(len(self.specs), atype.name, f"{atype.name}_{same_type}", dict(inst.type_bindings),
                         const_args, runtime, ports, states, {b.kind: b.code for b in atype.code}, impl,
                         location(atype.name_span), self.m.actor_costs.get(atype.name))
        self.specs.append(spec)
        self.spec_keys[key] = spec.id
        return spec.id

    # -------------------------------------------------------------- dataflows

    def lower_dataflows(self) -> None:
        for ch in self.timing.channels:
            c = ch.channel
            idx = len(self.channels)
            self.channel_index[c.name] = idx
            self.channels.append(Channel(idx, c.name, c.type, ch.capacity,
                                         [_runtime_value(c.type, v) for v in c.initial_tokens],
                                         self.task_index[ch.producer.name], self.task_index[ch.consumer.name],
                                         ch.tokens_in, ch.tokens_out, location(c.decl.name_span)))
        for df in self.m.dataflows.values():
            if df.task is None:  # run by no task: checked, not part of the program
                continue
            self.df_index[df.name] = len(self.dataflows)
            self.dataflows.append(self._dataflow(df))

    def _dataflow(self, df: DataflowInfo) -> Dataflow:
        did = len(self.dataflows)
        analysis = df.analysis
        instance_ids = []
        for name, inst in df.instances.items():
            spec = self.spec_for(inst)
            runtime_args = {n: self.expr(a.node) for n, a in inst.args.items() if a.const is None}
            iid = len(self.instances)
            self.instances.append(ActorInstance(iid, did, name, spec, runtime_args, location(inst.decl.name_span)))
            instance_ids.append(iid)
        sizes = {id(e): size for e, size in analysis.result.buffers + analysis.result.self_loops}
        buffers = []
        for e in df.edges:
            src, dst = analysis.node_of_edge[id(e)]
            sedge = next(g for g in analysis.graph.edges if g.loc == e.decl.span and g.src == src and g.dst == dst)
            buffers.append(Buffer(len(buffers), src, e.src.port, dst, e.dst.port, e.dst.type if e.dst.kind == "actor"
                                  else e.src.type, sedge.prod, sedge.cons, sizes[id(sedge)],
                                  [_runtime_value(e.dst.type, v) for v in e.initial_tokens], location(e.decl.span)))
        externals = []
        for node, ep in analysis.external_nodes.items():
            direction = "in" if node.startswith("in:") else "out"
            count = analysis.result.repetitions[node] * (ep.rate if ep.rate is not None else 1)
            if ep.kind == "channel":
                externals.append(External(node, direction, "channel", self.channel_index.get(ep.target.name, -1),
                                          count))
            else:
                externals.append(External(node, direction, "item", self.item_of[id(ep.target)], count))
        task = self.task_index.get(df.task.name) if df.task else None
        return Dataflow(did, df.name, instance_ids, buffers, externals, _activation_schedule(analysis, externals),
                        analysis.result.kind, dict(analysis.result.repetitions), task,
                        location(df.decl.name_span))

    # -------------------------------------------------------------- charts

    def lower_charts(self) -> None:
        for chart in self.m.charts.values():
            if chart.task is not None:
                self.charts.append(self._chart(chart))

    def _chart(self, chart: ChartInfo) -> Chart:
        branches: dict[tuple, int] = {}
        steps = []
        for s in chart.steps.values():
            slot = branches.setdefault(s.branch, len(branches))
            steps.append(Step(s.index, s.name, slot, s.decl.initial,
                              [Action(self.item_of[id(a.target)], self.expr(a.value), location(a.decl.span))
                               for a in s.entry_actions],
                              [Action(self.item_of[id(a.target)], self.expr(a.value), location(a.decl.span))
                               for a in s.exit_actions],
                              [self.df_index[d.name] for d in s.runs], location(s.decl.name_span)))
        transitions = [Transition(t.index, [s.index for s in t.sources], [s.index for s in t.targets],
                                  self.expr(t.guard), location(t.decl.span)) for t in chart.transitions]
        task = self.task_index.get(chart.task.name) if chart.task else None
        period_ms = int(chart.task.period_us) // 1000 if chart.task and chart.task.period_us % 1000 == 0 else None
        return Chart(len(self.charts), chart.name, steps, transitions, max(1, len(branches)),
                     chart.initial.index, task, period_ms, location(chart.decl.name_span))

    # -------------------------------------------------------------- tasks

    def lower_tasks(self) -> list[Task]:
        tasks = []
        tick = self.timing.tick_us
        for index, t in enumerate(self.timing.tasks):
            runs = []
            dataflows: list[int] = []
            for r in t.runs:
                if isinstance(r, DataflowInfo):
                    runs.append(("dataflow", self.df_index[r.name]))
                    dataflows.append(self.df_index[r.name])
                else:
                    c = next(c for c in self.charts if c.name == r.name)
                    runs.append(("chart", c.id))
                    for step in c.steps:
                        dataflows.extend(d for d in step.runs if d not in dataflows)
            reads, writes = set(), set()
            ch_in, ch_out = [], []
            for did in dataflows:
                for ext in self.dataflows[did].externals:
                    if ext.kind == "channel":
                        (ch_in if ext.direction == "in" else ch_out).append(ext.target)
                    elif ext.direction == "in":
                        reads.add(ext.target)
                    else:
                        writes.add(ext.target)
                for iid in self.dataflows[did].instances:
                    for node in self.instances[iid].runtime_args.values():
                        reads.update(self._refs(node))
            for r in t.runs:
                if isinstance(r, ChartInfo):
                    c = next(c for c in self.charts if c.name == r.name)
                    for tr in c.transitions:
                        reads.update(self._refs(tr.guard))
                    for step in c.steps:
                        for a in (*step.entry, *step.exit):
                            writes.add(a.target)
                            reads.update(self._refs(a.value))
            tasks.append(Task(index, t.name, int(t.period_us) // tick, int(t.offset_us) // tick,
                              int(t.deadline_us) // tick, int(t.wcet_us) if t.wcet_us is not None else None,
                              runs, sorted(reads | writes), sorted(writes), sorted(set(ch_in)),
                              sorted(set(ch_out)), location(t.decl.name_span)))
            for item_id in writes:
                self.items[item_id].writer_task = index
        for task in tasks:
            for item_id in task.reads:
                item = self.items[item_id]
                if item.kind == "dev_out":
                    dev = self.devices[item.device]
                    if task.id not in dev.read_by:
                        dev.read_by.append(task.id)
            for item_id in task.writes:
                item = self.items[item_id]
                if item.kind == "dev_in":
                    self.devices[item.device].written_by = task.id
        return tasks

    def _refs(self, node) -> set[int]:
        return {r.target for r in I.refs(node) if r.kind == "item"}

    def expr(self, node: I.IExpr) -> I.IExpr:
        """The IR form of a checked expression: references become ids (an
        item id, or a step id within its chart)."""
        if isinstance(node, I.Ref):
            if node.kind == "item":
                return I.Ref(node.type, "item", self.item_of[id(node.target)], node.name)
            return I.Ref(node.type, node.kind, node.target.index, node.name)
        if isinstance(node, I.Unary):
            return I.Unary(node.type, node.op, self.expr(node.arg))
        if isinstance(node, I.Convert):
            return I.Convert(node.type, self.expr(node.arg))
        if isinstance(node, I.Binary):
            return I.Binary(node.type, node.op, self.expr(node.left), self.expr(node.right), node.operand_type)
        return node


def _activation_schedule(analysis, externals: list[External]) -> Schedule:
    """The analysis's schedule with the item endpoints moved out of the way:
    every ``in:`` item node fires first and every ``out:`` item node last, so
    a dataflow that writes a var and also reads it sees the value latched at
    release whatever the schedule (docs/ir.md, "dataflows"). They fire once
    per activation, so they sit at the top level of any schedule."""
    items = {e.node: e for e in externals if e.kind == "item"}
    body = analysis.result.schedule.body
    moved = [n for n in body if isinstance(n, Fire) and n.actor in items]
    assert len(moved) == len(items), "item endpoints fire once per activation, at the top level"
    rest = tuple(n for n in body if not (isinstance(n, Fire) and n.actor in items))
    first = tuple(Fire(e.node) for e in externals if e.kind == "item" and e.direction == "in")
    last = tuple(Fire(e.node) for e in externals if e.kind == "item" and e.direction == "out")
    return Schedule(first + rest + last)


def lower(model: CheckedModel, timing: Timing) -> Program:
    """Lower a checked and analysed model to the IR."""
    low = _Lowering(model, timing)
    low.lower_items()
    low.lower_dataflows()
    low.lower_charts()
    tasks = low.lower_tasks()
    instants = [Instant(i.tick, list(i.publish), list(i.release)) for i in timing.instants]
    interfaces = [Interface(i.kind, str(i.claim) if i.claim else None, dict(i.settings)) for i in model.interfaces]
    program = Program(model.name, model.title, model.file, 0, timing.tick_us, timing.hyperperiod_ticks,
                      low.items, low.devices, low.specs, low.instances, low.dataflows, low.charts, low.channels,
                      tasks, instants, interfaces)
    if model.nodes:
        program.deployment = _deployment(model, timing, program, low)
    if model.remote is not None:
        r = model.remote
        watchdog = next((str(a.value.span) for a in r.decl.attrs if a.key == "watchdog"), location(r.decl.span))
        program.remote = RemoteSettings(r.watchdog_us, r.overrun_limit, location(r.decl.span), watchdog)
    program.program_id = program_id(program)
    return program


def _deployment(model: CheckedModel, timing: Timing, program: Program, low: _Lowering) -> Deployment:
    """Where each task and device runs, the links and what crosses them."""
    nodes = [NodeSpec(n.name, n.board, n.mcu, n.decl.title, n.decl.cores or 1) for n in model.nodes.values()]
    links = [LinkSpec(lk.name, lk.engine, dict(lk.settings),
                      [LinkMember(m.node.name, m.role, str(m.uart) if m.uart else None, m.unit) for m in lk.members])
             for lk in model.links.values()]
    task_nodes = {t.id: model.task_nodes[t.name] for t in program.tasks}
    device_nodes = {d.id: model.device_nodes[d.path] for d in program.devices}
    plan = timing.links
    crossings = [Crossing(low.channel_index[name], c.link, c.producer_node, c.consumer_node, c.dds_delay_us)
                 for name, c in (plan.carriages.items() if plan else ())]
    exports = []
    for e in model.exports:
        kind = "channel" if e.target.name in model.channels else "var"
        target = low.channel_index[e.target.name] if kind == "channel" else low.item_of[id(e.target)]
        exports.append(ExportSpec(e.target.name, kind, target, e.link.name, e.node.name,
                                  topic_name(model.name, e.node.name, e.target.name)))
    return Deployment(nodes, links, task_nodes, device_nodes, crossings, exports, dict(plan.rounds) if plan else {})
