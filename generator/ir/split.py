"""One program per node, from the program of a distributed model
(docs/distribution.md, "The split").

Each node's program is a :class:`~.program.Program` of its own, numbered
from 0 like any program: the node's tasks (in the whole model's dispatch
order), the actors, dataflows and charts they run, its devices, the items
its tasks read or write, its channels, and a dispatch table recomputed for
its tasks alone (their tick and hyperperiod), and, on a slave of a Modbus
link, the link's Modbus RTU slave interface on its UART; its status items
(``ir/status.py``: the links' fault counters), with a debug interface of its
own on a node that is no slave. A channel that crosses to
another node keeps one end here: an **output** (its consumer task is on
another node, ``consumer_task`` is None) or an **input** (``producer_task``
is None); the link moves its tokens between the two ends.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from math import gcd

from ..core import expr as I
from .dds import node_dds_channels, node_exports
from .deployment import Crossing, NodeSpec
from .program import Chart, Dataflow, Instant, Interface, Program, Task, program_id
from .status import node_status


@dataclass
class ChannelEnd:
    """A node's end of a channel that crosses a link."""

    channel: int  # the channel's id in the node's program
    name: str
    link: str
    other_node: str  # the node of the other end


@dataclass
class NodeProgram:
    node: NodeSpec
    program: Program
    inputs: list[ChannelEnd]  # channels whose producer is on another node
    outputs: list[ChannelEnd]  # channels whose consumer is on another node
    rounds: list[object]  # the round tables of the Modbus links the node is on (analysis.distribution.RoundTable)


def split(program: Program) -> dict[str, NodeProgram]:
    """The program of each node of a distributed program, by node name (in
    declaration order). A program without a deployment is one node's: it
    cannot be split (ValueError)."""
    deployment = program.deployment
    if deployment is None:
        raise ValueError(f"model '{program.name}' has no nodes to split it into")
    return {node.name: _node_program(program, node) for node in deployment.nodes}


class _Numbering:
    """Old ids -> new ids, in the order of the old ones."""

    def __init__(self, old_ids) -> None:
        self.new = {old: new for new, old in enumerate(sorted(set(old_ids)))}

    def __call__(self, old: int | None) -> int | None:
        return None if old is None else self.new.get(old)

    def __contains__(self, old: int) -> bool:
        return old in self.new

    def kept(self, things: list) -> list:
        return [things[old] for old in sorted(self.new)]


def _node_program(program: Program, node: NodeSpec) -> NodeProgram:
    dep = program.deployment
    tasks = _Numbering(t.id for t in program.tasks if dep.task_nodes[t.id] == node.name)
    devices = _Numbering(d.id for d in program.devices if dep.device_nodes[d.id] == node.name)
    dataflows = _Numbering(df.id for df in program.dataflows if df.task in tasks)
    charts = _Numbering(c.id for c in program.charts if c.task in tasks)
    channels = _Numbering(c.id for c in program.channels
                          if c.producer_task in tasks or c.consumer_task in tasks)
    item_ids = {i for t in program.tasks if t.id in tasks for i in (*t.reads, *t.writes)}
    item_ids |= {i for d in program.devices if d.id in devices for i in d.items}
    items = _Numbering(item_ids)
    instances = _Numbering(a.id for a in program.instances if a.dataflow in dataflows)
    specs = _Numbering(program.instances[a].spec for a in instances.new)

    def expr(e: I.IExpr) -> I.IExpr:
        if isinstance(e, I.Ref):
            return replace(e, target=items(e.target)) if e.kind == "item" else e
        if isinstance(e, (I.Unary, I.Convert)):
            return replace(e, arg=expr(e.arg))
        if isinstance(e, I.Binary):
            return replace(e, left=expr(e.left), right=expr(e.right))
        return e

    new_items = [replace(i, id=items(i.id), device=devices(i.device), writer_task=tasks(i.writer_task))
                 for i in items.kept(program.items)]
    new_devices = [replace(d, id=devices(d.id), items=[items(i) for i in d.items],
                           read_by=[tasks(t) for t in d.read_by], written_by=tasks(d.written_by))
                   for d in devices.kept(program.devices)]
    new_specs = [replace(s, id=specs(s.id)) for s in specs.kept(program.specs)]
    new_instances = [replace(a, id=instances(a.id), dataflow=dataflows(a.dataflow), spec=specs(a.spec),
                             runtime_args={k: expr(v) for k, v in a.runtime_args.items()})
                     for a in instances.kept(program.instances)]
    new_dataflows = [_dataflow(df, dataflows, instances, items, channels, tasks)
                     for df in dataflows.kept(program.dataflows)]
    new_charts = [_chart(c, charts, dataflows, items, tasks, expr) for c in charts.kept(program.charts)]
    # The initial tokens of a crossing channel are its consumer's: an output end starts empty.
    new_channels = [replace(c, id=channels(c.id), producer_task=tasks(c.producer_task),
                            consumer_task=tasks(c.consumer_task),
                            initial=c.initial if c.consumer_task in tasks else [])
                    for c in channels.kept(program.channels)]
    new_tasks = [_task(t, tasks, dataflows, charts, items, channels) for t in tasks.kept(program.tasks)]
    tick, hyper, instants = _dispatch(program, new_tasks, tasks)
    new_tasks = [replace(t, period=t.period * program.tick_us // tick, offset=t.offset * program.tick_us // tick,
                         deadline=t.deadline * program.tick_us // tick) for t in new_tasks]
    node_program = Program(f"{program.name}.{node.name}", program.title, program.source, 0, tick, hyper, new_items,
                           new_devices, new_specs, new_instances, new_dataflows, new_charts, new_channels,
                           new_tasks, instants, _link_interfaces(program, node.name))
    node_program.exports = node_exports(program, node.name, items, channels, tasks)
    node_program.dds_channels = node_dds_channels(program, node.name, channels)
    inputs, outputs = [], []
    for crossing in dep.crossings:
        end = _end(crossing, node.name, channels, program)
        if end is not None:
            (outputs if crossing.producer_node == node.name else inputs).append(end)
    rounds = [table for name, table in dep.rounds.items()
              if any(m.node == node.name for lk in dep.links if lk.name == name for m in lk.members)]
    mastered = [table for table in rounds if table.master == node.name]
    node_program.status = node_status(node_program, [(end.channel, end.name) for end in inputs],
                                      [slot.node for table in mastered for slot in table.slots], program.source)
    if node_program.status and not node_program.interfaces:
        # A node that is no Modbus slave (a PC: the master, a DDS peer) serves its status items on a
        # debug interface of its own, where its process is told (`easylab launch --debug`); a slave
        # serves them as input registers of its Modbus RTU slave on the link.
        node_program.interfaces = [Interface("debug", None, {})]
    node_program.program_id = program_id(node_program)
    return NodeProgram(node, node_program, inputs, outputs, rounds)


def _link_interfaces(program: Program, node: str) -> list[Interface]:
    """A slave of a Modbus link is a Modbus RTU slave on its UART: the
    link's baud rate and parity, its unit id."""
    found = []
    for link in program.deployment.links:
        for m in link.members:
            if m.node == node and m.role == "slave":
                found.append(Interface("modbus-rtu", m.uart, {"baud": link.settings["baud"],
                                                              "parity": link.settings["parity"], "unit": m.unit}))
    return found


def _end(crossing: Crossing, node: str, channels: _Numbering, program: Program) -> ChannelEnd | None:
    if node not in (crossing.producer_node, crossing.consumer_node):
        return None
    other = crossing.consumer_node if crossing.producer_node == node else crossing.producer_node
    return ChannelEnd(channels(crossing.channel), program.channels[crossing.channel].name, crossing.link, other)


def _dataflow(df: Dataflow, dataflows, instances, items, channels, tasks) -> Dataflow:
    externals = [replace(e, target=items(e.target) if e.kind == "item" else channels(e.target))
                 for e in df.externals]
    return replace(df, id=dataflows(df.id), instances=[instances(i) for i in df.instances], externals=externals,
                   task=tasks(df.task))


def _chart(c: Chart, charts, dataflows, items, tasks, expr) -> Chart:
    def action(a):
        return replace(a, target=items(a.target), value=expr(a.value))

    steps = [replace(s, entry=[action(a) for a in s.entry], exit=[action(a) for a in s.exit],
                     runs=[dataflows(d) for d in s.runs]) for s in c.steps]
    transitions = [replace(t, guard=expr(t.guard)) for t in c.transitions]
    return replace(c, id=charts(c.id), steps=steps, transitions=transitions, task=tasks(c.task))


def _task(t: Task, tasks, dataflows, charts, items, channels) -> Task:
    runs = [(kind, dataflows(i) if kind == "dataflow" else charts(i)) for kind, i in t.runs]
    return replace(t, id=tasks(t.id), runs=runs, reads=[items(i) for i in t.reads],
                   writes=[items(i) for i in t.writes], channels_in=[channels(c) for c in t.channels_in],
                   channels_out=[channels(c) for c in t.channels_out])


def _lcm(a: int, b: int) -> int:
    return a // gcd(a, b) * b


def _dispatch(program: Program, node_tasks: list[Task], numbering: _Numbering) -> tuple[int, int, list[Instant]]:
    """The node's tick (µs), hyperperiod (its ticks) and dispatch table: the
    whole program's table restricted to the node's tasks over their own
    hyperperiod (which divides the whole one)."""
    us = program.tick_us
    tick, hyper_us = 0, 1
    for t in node_tasks:
        for value in (t.period, t.offset, t.deadline):
            tick = gcd(tick, value * us)
        hyper_us = _lcm(hyper_us, t.period * us)
    if not node_tasks:
        return program.tick_us, 1, []
    instants = []
    for instant in program.instants:
        at = instant.tick * us
        publish = [numbering(t) for t in instant.publish if t in numbering]
        release = [numbering(t) for t in instant.release if t in numbering]
        if at < hyper_us and (publish or release):
            instants.append(Instant(at // tick, publish, release))
    return tick, hyper_us // tick, instants


__all__ = ["ChannelEnd", "NodeProgram", "split"]
