"""Live replacement of the model (docs/local.md, "Live replacement"): what
carries over from the running program to the new one (items, actors'
state, delay tokens, chart steps, channels, publications still due), and
the report of what did."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..ir.program import Item
from .charts import ChartRunner
from .dataflow import ActorState
from .state import ProgramState, TaskState


# ====================================================================== replacement


@dataclass
class CarriedPublication:
    """What a task of a replaced program still had to publish: its outputs
    by name, delivered into the new program at the old deadline."""

    due_us: int
    task: str
    items: dict[str, tuple[Item, list]]
    channels: dict[str, tuple[object, list]]
    charts: dict[str, set[str]]

    def deliver(self, state: ProgramState) -> None:
        items = {i.name: i for i in state.program.items}
        for name, (old, values) in self.items.items():
            new = items.get(name)
            if new is not None and new.type == old.type and new.count == old.count:
                state.published[new.id][:] = values
        for ch_id, ch in enumerate(state.program.channels):
            if ch.name in self.channels and self.channels[ch.name][0] == ch.type:
                state.channels[ch_id].extend(self.channels[ch.name][1])
        for runner in state.charts:
            if runner.chart.name in self.charts:
                active = self.charts[runner.chart.name]
                runner.active = [s.name in active for s in runner.chart.steps]


@dataclass
class Replacement:
    """What a live replacement kept and what it started afresh (by name)."""

    time_us: int
    old_id: int
    new_id: int
    kept_actors: list[str] = field(default_factory=list)
    new_actors: list[str] = field(default_factory=list)
    dropped_actors: list[str] = field(default_factory=list)
    kept_items: list[str] = field(default_factory=list)
    reset_items: list[str] = field(default_factory=list)
    kept_charts: list[str] = field(default_factory=list)
    restarted_charts: list[str] = field(default_factory=list)
    carried_tasks: list[str] = field(default_factory=list)
    untraced: list[str] = field(default_factory=list)  # new items and charts the trace lacks
    frozen: list[str] = field(default_factory=list)  # trace columns that keep their last value
    ignored_stimulus: list[str] = field(default_factory=list)  # stimulus columns whose item is gone


def _same_item(a: Item, b: Item) -> bool:
    """An item keeps its value when its declaration is unchanged (an edited
    initial value or range takes effect)."""
    return (a.kind, a.type, a.count, a.initial, a.range) == (b.kind, b.type, b.count, b.initial, b.range)


def transfer(old: ProgramState, new: ProgramState, report: Replacement) -> None:
    """Carry the state of what exists in both programs into ``new``
    (docs/local.md, "Live replacement")."""
    _transfer_items(old, new, report)
    _transfer_actors(old, new, report)
    _transfer_delay_tokens(old, new)
    _transfer_charts(old, new, report)
    _transfer_channels(old, new)


def _transfer_items(old: ProgramState, new: ProgramState, report: Replacement) -> None:
    old_items = {i.name: i for i in old.program.items}
    for item in new.program.items:
        previous = old_items.get(item.name)
        if previous is not None and _same_item(previous, item):
            new.published[item.id][:] = old.published[previous.id][:]
            report.kept_items.append(item.name)
        elif previous is not None:
            report.reset_items.append(item.name)


def _actor_key(state: ProgramState, actor: ActorState) -> str:
    """What names an actor instance across programs: "Dataflow.instance"."""
    return f"{state.program.dataflows[actor.instance.dataflow].name}.{actor.instance.name}"


def _transfer_actors(old: ProgramState, new: ProgramState, report: Replacement) -> None:
    """Instances with the same name and plug-in keep their state; the others
    start, and the old ones nothing took over stop."""
    old_actors = {_actor_key(old, a): a for a in old.actors}
    started = []
    for actor in new.actors:
        key = _actor_key(new, actor)
        previous = old_actors.get(key)
        if previous is not None and previous.plugin.digest == actor.plugin.digest:
            actor.take_state_from(previous)
            del old_actors[key]
            report.kept_actors.append(key)
        else:
            started.append(actor)
            report.new_actors.append(key)
    for key, actor in old_actors.items():
        actor.stop()
        report.dropped_actors.append(key)
    for actor in started:
        actor.start()


def _transfer_delay_tokens(old: ProgramState, new: ProgramState) -> None:
    """An unchanged edge with initial tokens keeps the tokens it holds."""
    def shape(edge):
        b = edge.buffer
        return b.src, b.src_port, b.dst, b.dst_port, b.type, edge.delay
    old_flows = {r.dataflow.name: r for r in old.dataflows if r is not None}
    for runner in new.dataflows:
        previous = old_flows.get(runner.dataflow.name) if runner is not None else None
        if previous is None:
            continue
        old_edges = {shape(e): e for e in previous.buffers if e.delay}
        for edge in runner.buffers:
            match = old_edges.get(shape(edge)) if edge.delay else None
            if match is not None:
                edge.set_delay_tokens(match.delay_tokens())


def _transfer_charts(old: ProgramState, new: ProgramState, report: Replacement) -> None:
    """A chart with the same steps (names and branches) keeps its slots,
    step times and activity (and its last fired transition when its
    transitions are the same); another restarts at its initial step."""
    def shape(runner: ChartRunner):
        return [(s.name, s.slot) for s in runner.chart.steps], runner.chart.slots
    old_charts = {r.chart.name: r for r in old.charts}
    for runner in new.charts:
        previous = old_charts.get(runner.chart.name)
        if previous is not None and shape(previous) == shape(runner):
            runner.slots = list(previous.slots)
            runner.elapsed = list(previous.elapsed)
            runner.started = previous.started
            runner.active = list(previous.active)
            # the transition fired last, while its number names the same transition
            if _transitions(previous.chart) == _transitions(runner.chart):
                runner.fired = previous.fired
            report.kept_charts.append(runner.chart.name)
        elif previous is not None:
            report.restarted_charts.append(runner.chart.name)


def _transitions(chart) -> list:
    """A chart's transitions by the names of their source and target steps."""
    return [([chart.steps[s].name for s in t.sources], [chart.steps[s].name for s in t.targets])
            for t in chart.transitions]


def _transfer_channels(old: ProgramState, new: ProgramState) -> None:
    old_channels = {c.name: (c, old.channels[c.id]) for c in old.program.channels}
    for ch in new.program.channels:
        if ch.name in old_channels and old_channels[ch.name][0].type == ch.type:
            new.channels[ch.id].replace(old_channels[ch.name][1].tokens())


def carry(old: ProgramState, task_state: TaskState) -> CarriedPublication:
    """A released, unpublished activation of the old program, to deliver."""
    program, task = old.program, task_state.task
    due = task_state.released_at_us + task.deadline * program.tick_us
    items = {program.items[i].name: (program.items[i], list(task_state.local[i])) for i in task.writes}
    channels = {program.channels[c].name: (program.channels[c].type,
                                           task_state.staging[c].values())
                for c in task.channels_out}
    charts = {}
    for cid in old.charts_of_task[task.id]:
        runner = old.charts[cid]
        charts[runner.chart.name] = {s.name for s in runner.chart.steps if runner.slots[s.slot] == s.id}
    return CarriedPublication(due, task.name, items, channels, charts)


