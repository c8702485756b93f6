"""Task timing under logical execution time: the tick, the hyperperiod, the
dispatch table, channels between tasks and wcet schedulability.

Run after the SDF analysis. Everything here is exact integer arithmetic on
microseconds; errors go to the diagnostics like the checker's.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from math import gcd

from ..core.expr import refs
from .distribution import Carriage, LinkPlan, plan_links, worst_latency_us
from ..frontend.model import ChannelInfo, CheckedModel, DataflowInfo, TaskInfo
from ..core.source import Diagnostics, note

MAX_TASKS = 32  # the dispatcher's task masks are 32 bits wide
MAX_INSTANTS = 65535
MAX_CHANNEL_CAPACITY = 65535


def _lcm(a: int, b: int) -> int:
    return a // gcd(a, b) * b


@dataclass
class Instant:
    """One entry of the dispatch table: at ``tick`` (within the hyperperiod),
    publish the outputs of ``publish`` (tasks whose deadline it is), then
    release ``release``."""

    tick: int
    publish: list[int] = field(default_factory=list)
    release: list[int] = field(default_factory=list)


@dataclass
class ChannelTiming:
    channel: ChannelInfo
    producer: TaskInfo
    consumer: TaskInfo
    tokens_in: int   # produced per producer activation
    tokens_out: int  # consumed per consumer activation
    capacity: int


@dataclass
class Timing:
    tick_us: int
    hyperperiod_ticks: int
    tasks: list[TaskInfo]           # in dispatch order: by deadline, then declaration
    instants: list[Instant]
    channels: list[ChannelTiming]
    utilisation: float | None       # sum of wcet / period where every task has a wcet
    links: LinkPlan | None = None   # a model of nodes: the links' rounds and the channels crossing them


def _ticks(us, tick_us: int) -> int:
    return int(us) // tick_us


def compute_timing(model: CheckedModel, diags: Diagnostics) -> Timing | None:
    """The dispatch table of the model's tasks, or None after errors."""
    tasks = list(model.tasks.values())
    if len(tasks) > MAX_TASKS:
        diags.error(tasks[MAX_TASKS].decl.name_span, f"a model has at most {MAX_TASKS} tasks")
        return None
    ok = _check_step_time(model, diags)
    if not tasks:
        return Timing(1000, 1, [], [], [], None) if ok else None
    tick = 0
    hyper = 1
    for t in tasks:
        for value in (t.period_us, t.offset_us, t.deadline_us):
            tick = gcd(tick, int(value))
        hyper = _lcm(hyper, int(t.period_us))
    hyper_ticks = hyper // tick
    instants: dict[int, Instant] = {}
    count = sum(hyper // int(t.period_us) * 2 for t in tasks)
    if count > MAX_INSTANTS * 2:
        diags.error(tasks[0].decl.name_span,
                    f"the tasks' hyperperiod of {hyper} us holds {count} releases and deadlines, more than "
                    f"the dispatch table can hold; choose periods with a smaller least common multiple")
        return None
    order = sorted(range(len(tasks)), key=lambda i: (tasks[i].deadline_us, i))
    ordered = [tasks[i] for i in order]
    for index, t in enumerate(ordered):
        period, offset, deadline = (_ticks(t.period_us, tick), _ticks(t.offset_us, tick),
                                    _ticks(t.deadline_us, tick))
        for k in range(hyper_ticks // period):
            release = offset + k * period
            instants.setdefault(release % hyper_ticks, Instant(release % hyper_ticks)).release.append(index)
            end = (release + deadline) % hyper_ticks
            instants.setdefault(end, Instant(end)).publish.append(index)
    table = [instants[k] for k in sorted(instants)]
    if len(table) > MAX_INSTANTS:
        diags.error(tasks[0].decl.name_span, f"the dispatch table would have {len(table)} instants "
                                             f"(at most {MAX_INSTANTS})")
        return None
    links = plan_links(model, diags) if model.links else None
    if model.links and links is None:
        return None
    channels = _check_channels(model, ordered, tick, hyper_ticks, diags, links)
    utilisation = None
    if all(t.wcet_us is not None for t in tasks):
        utilisation = float(sum(t.wcet_us / t.period_us for t in tasks))
        if utilisation > 1:
            diags.error(tasks[0].decl.name_span,
                        f"the tasks' wcet add up to {utilisation:.0%} of the processor: not schedulable",
                        "shorten a wcet or lengthen a period")
            ok = False
        else:
            ok = _check_wcet(ordered, tick, hyper_ticks, diags) and ok
    if channels is None or not ok:
        return None
    return Timing(tick, hyper_ticks, ordered, table, channels, utilisation, links)


def _check_wcet(tasks: list[TaskInfo], tick: int, hyper: int, diags: Diagnostics) -> bool:
    """Non-preemptive EDF simulation over one hyperperiod (two, for offsets):
    every job must finish by its deadline given the declared wcets."""
    jobs = []
    for t in tasks:
        period, offset, deadline = _ticks(t.period_us, tick), _ticks(t.offset_us, tick), _ticks(t.deadline_us, tick)
        for k in range(2 * hyper // period):
            release = offset + k * period
            jobs.append((release, release + deadline, t))
    jobs.sort(key=lambda j: (j[0], j[1]))
    now = 0
    pending: list = []
    i = 0
    while i < len(jobs) or pending:
        if not pending:
            now = max(now, jobs[i][0] * tick)
        while i < len(jobs) and jobs[i][0] * tick <= now:
            pending.append(jobs[i])
            i += 1
        pending.sort(key=lambda j: j[1])
        release, deadline, t = pending.pop(0)
        now += int(t.wcet_us)
        if now > deadline * tick:
            diags.error(t.decl.name_span, f"task '{t.name}' can miss its deadline: with the declared wcets "
                                          f"its job released at {release * tick} us ends at {now} us, after "
                                          f"its deadline at {deadline * tick} us")
            return False
    return True


def _check_step_time(model: CheckedModel, diags: Diagnostics) -> bool:
    """``Step.time`` advances by the task period: it must be whole ms."""
    ok = True
    for chart in model.charts.values():
        uses = [r for tr in chart.transitions if tr.guard is not None for r in refs(tr.guard)
                if r.kind == "step_time"]
        for step in chart.steps.values():
            for action in (*step.entry_actions, *step.exit_actions):
                uses.extend(r for r in refs(action.value) if r.kind == "step_time")
        if uses and chart.task is not None and chart.task.period_us % 1000 != 0:
            diags.error(chart.task.decl.name_span,
                        f"chart '{chart.name}' uses step times, which count milliseconds, but task "
                        f"'{chart.task.name}' has a period of {chart.task.period_us} us",
                        "give the task a period of whole milliseconds")
            ok = False
    return ok


def _owner_task(df: DataflowInfo, diags: Diagnostics, ch: ChannelInfo) -> TaskInfo | None:
    if df.task is None:
        diags.error(ch.decl.name_span, f"channel '{ch.name}' connects dataflow '{df.name}', which no task runs")
        return None
    if not any(r is df for r in df.task.runs):
        diags.error(ch.decl.name_span, f"channel '{ch.name}' is used by dataflow '{df.name}', which runs inside "
                                       "a chart: a channel needs a dataflow its task runs at every activation",
                    f"run '{df.name}' directly in task '{df.task.name}'")
        return None
    return df.task


def _check_channels(model: CheckedModel, tasks: list[TaskInfo], tick: int, hyper: int,
                    diags: Diagnostics, links: LinkPlan | None = None) -> list[ChannelTiming] | None:
    result = []
    ok = True
    for ch in model.channels.values():
        if not ch.producers or not ch.consumers:
            continue  # reported by the checker
        prod_edge, cons_edge = ch.producers[0], ch.consumers[0]
        prod_df = next(df for df in model.dataflows.values() if prod_edge in df.edges)
        cons_df = next(df for df in model.dataflows.values() if cons_edge in df.edges)
        if prod_df.analysis is None or cons_df.analysis is None:
            continue  # an SDF error, reported already
        p_task, c_task = _owner_task(prod_df, diags, ch), _owner_task(cons_df, diags, ch)
        if p_task is None or c_task is None:
            ok = False
            continue
        if p_task is c_task:
            diags.error(ch.decl.name_span, f"channel '{ch.name}' connects two dataflows of task '{p_task.name}'",
                        "inside one task, connect the dataflows through a var, or merge them")
            ok = False
            continue
        n_in = prod_df.analysis.result.repetitions["out:" + ch.name]
        n_out = cons_df.analysis.result.repetitions["in:" + ch.name]
        rate_in = n_in / p_task.period_us
        rate_out = n_out / c_task.period_us
        if rate_in != rate_out:
            diags.error(ch.decl.name_span,
                        f"channel '{ch.name}' does not balance: task '{p_task.name}' puts {n_in} token(s) in "
                        f"every {_us(p_task.period_us)}, task '{c_task.name}' takes {n_out} every "
                        f"{_us(c_task.period_us)}",
                        notes=(note(prod_edge.decl.span, "produced here"), note(cons_edge.decl.span, "consumed here")))
            ok = False
            continue
        carriage = links.carriages.get(ch.name) if links is not None else None
        missing, capacity = _channel_simulation(ch, tasks.index(p_task), tasks.index(c_task), tasks,
                                                n_in, n_out, tick, hyper, carriage)
        if missing > 0 and carriage is not None:
            have = len(ch.initial_tokens)
            latency = worst_latency_us(carriage, _publications(p_task, tick, hyper))
            diags.error(ch.decl.name_span,
                        f"channel '{ch.name}' runs dry: it crosses link '{carriage.link}' from node "
                        f"'{carriage.producer_node}' to node '{carriage.consumer_node}', where a value reaches "
                        f"task '{c_task.name}' up to {latency} us after task '{p_task.name}' publishes it; it "
                        f"needs {missing} more initial token(s)",
                        f"declare it with: delay {have + missing}")
            ok = False
            continue
        if missing > 0:
            have = len(ch.initial_tokens)
            diags.error(ch.decl.name_span,
                        f"channel '{ch.name}' runs dry: task '{c_task.name}' takes {n_out} token(s) at a release "
                        f"before enough have been published; it needs {missing} more initial token(s)",
                        f"declare it with: delay {have + missing}")
            ok = False
            continue
        if capacity > MAX_CHANNEL_CAPACITY:
            diags.error(ch.decl.name_span, f"channel '{ch.name}' would need {capacity} tokens of storage "
                                           f"(at most {MAX_CHANNEL_CAPACITY})")
            ok = False
            continue
        result.append(ChannelTiming(ch, p_task, c_task, n_in, n_out, capacity))
    return result if ok else None


def _us(us) -> str:
    us = int(us)
    for unit, scale in (("s", 1_000_000), ("ms", 1000)):
        if us % scale == 0:
            return f"{us // scale} {unit}"
    return f"{us} us"


def _publications(task: TaskInfo, tick: int, hyper: int, hyperperiods: int = 1) -> list[int]:
    """The task's deadlines (when its outputs are published), in microseconds."""
    period, offset, deadline = (_ticks(task.period_us, tick), _ticks(task.offset_us, tick),
                                _ticks(task.deadline_us, tick))
    return [(offset + k * period + deadline) * tick for k in range(hyperperiods * hyper // period)]


def _channel_simulation(ch, p_index, c_index, tasks, n_in, n_out, tick, hyper, carriage: Carriage | None = None):
    """Tokens over two hyperperiods: publications at the producer's deadlines
    come before releases at the same instant. A channel that crosses a link
    publishes at each value's arrival on the consumer's node instead, over
    two periods of the pattern that the tasks and the link's round repeat.
    Returns (missing, capacity)."""
    p, c = tasks[p_index], tasks[c_index]
    if carriage is not None and carriage.round is not None:
        hyper = _lcm(hyper * tick, carriage.round.period_us) // tick
    events = []
    for d in _publications(p, tick, hyper, 2):
        events.append((carriage.arrival(d) if carriage is not None else d, 0, n_in))
    period, offset = _ticks(c.period_us, tick), _ticks(c.offset_us, tick)
    for k in range(2 * hyper // period):
        events.append(((offset + k * period) * tick, 1, -n_out))
    events.sort()
    level = low = len(ch.initial_tokens)
    high = level
    for _, _, delta in events:
        level += delta
        low = min(low, level)
        high = max(high, level)
    missing = -low if low < 0 else 0
    return missing, high + missing
