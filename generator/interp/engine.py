"""The interpreter of the IR: LET dispatcher, tasks, channels, devices, and
live replacement of the model (docs/local.md).

:class:`ProgramState` is everything one program holds at run time (the
published items, each task's local copies, channels, actor instances,
dataflows and charts); :class:`Engine` walks the program's dispatch table
(docs/ir.md, "Tasks and logical execution time") and can swap in a new
program between two instants (:meth:`Engine.replace_model`), carrying the
state of whatever did not change.
"""

from __future__ import annotations

import queue
import shutil
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..ir import Instant, Item, Program, Task
from . import values as V
from .charts import ChartRunner
from .dataflow import ActorState, DataflowRunner
from .interfaces import LOAD_REFUSED, LOAD_REPLACED, PROBE, Interfaces, Library
from .plugins import Plugin, PluginCache, PluginError
from .stimulus import Stimulus
from .trace import Sampler, TraceWriter, columns_of


# ====================================================================== one program


class TaskState:
    """A task's local copies (by item id; None for items it does not use),
    its channel staging arrays and cursors, and whether an activation waits
    for its deadline."""

    def __init__(self, task: Task, program: Program):
        self.task = task
        self.local: list[list | None] = [None] * len(program.items)
        self.staging: dict[int, list] = {}
        self.cursor: dict[int, int] = {}
        for ch in task.channels_in:
            self.staging[ch] = []
        for ch in task.channels_out:
            channel = program.channels[ch]
            self.staging[ch] = [V.zero(channel.type)] * channel.tokens_in
        self.pending = False
        self.released_at_us = 0

    # Moves between the task's copies and dataflow edges (DataflowRunner).

    def item_to_edge(self, item: int, array, lo: int, hi: int) -> None:
        array[lo:hi] = self.local[item]

    def edge_to_item(self, item: int, array, lo: int, hi: int) -> None:
        self.local[item] = array[lo:hi]

    def channel_to_edges(self, channel: int, targets: list) -> None:
        token = self.staging[channel][self.cursor[channel]]
        for array, at in targets:
            array[at] = token
        self.cursor[channel] += 1

    def edge_to_channel(self, channel: int, array, at: int) -> None:
        self.staging[channel][self.cursor[channel]] = array[at]
        self.cursor[channel] += 1


class ProgramState:
    """The run-time state of one program, built from its IR and plug-ins
    (``plugins[spec id]``, ``run_batch`` the batch runner of
    plugins.BATCH_SOURCE), as the firmware holds it at boot."""

    def __init__(self, program: Program, plugins: list[Plugin], run_batch: Callable[[int, int], None],
                 io: Interfaces | None = None):
        self.program = program
        self.plugins = plugins
        self.io = io
        self.published: list[list] = [[V.literal(i.type, i.initial)] * i.count for i in program.items]
        self.tasks = [TaskState(t, program) for t in program.tasks]
        self.channels = [deque(V.literal(c.type, v) for v in c.initial) for c in program.channels]
        self.actors = [ActorState(inst, program.specs[inst.spec], plugins[inst.spec],
                                  io.actor_states[inst.id] if io is not None else None)
                       for inst in program.instances]
        self.dataflows: list[DataflowRunner | None] = []
        for df in program.dataflows:
            if df.task is None:  # run by no task: never runs
                self.dataflows.append(None)
                continue
            actors = {self.actors[i].instance.name: self.actors[i] for i in df.instances}
            self.dataflows.append(DataflowRunner(program, df, actors, self.tasks[df.task], run_batch))
        self.charts = [ChartRunner(program, c, self.tasks[c.task] if c.task is not None else None,
                                   self.run_dataflow) for c in program.charts]
        self.instants = program.instants or [Instant(0, [], [])]  # as the C table: one empty instant
        self.readers = [(d.id, set(d.read_by)) for d in program.devices if d.read_by]
        self.charts_of_task = [[cid for kind, cid in t.runs if kind == "chart"] for t in program.tasks]
        if io is not None and io.has_debug:  # the debugger's probes where the firmware has them
            for runner in self.dataflows:
                if runner is not None:
                    runner.probe_actor = self._probe_actor
                    runner.armed = lambda: io.armed
            for chart in self.charts:
                chart.probe = self.probe

    def serve(self, call: Callable, *args) -> None:
        """Call into the interfaces library (which may serve clients): the
        published items go in before, what clients wrote comes back after."""
        io = self.io
        io.push(self.published, self.charts)
        call(*args)
        io.pull(self.published)

    def probe(self, kind: str, a: int, b: int = 0) -> None:
        """The debugger's probe (EL_DEBUG_PROBE): a call into the server
        only when it is armed (a breakpoint, a step or a break pending)."""
        if self.io.armed:
            self.serve(self.io.probe, PROBE[kind], a, b)

    def _probe_actor(self, instance: int) -> None:
        self.probe("actor", instance)

    def run_dataflow(self, dataflow: int) -> None:
        self.dataflows[dataflow].run()

    def release(self, task_state: TaskState) -> None:
        """Latch the task's items and take its channel tokens."""
        local, published = task_state.local, self.published
        for item in task_state.task.reads:
            local[item] = list(published[item])
        for ch in task_state.task.channels_in:
            ring = self.channels[ch]
            task_state.staging[ch] = [ring.popleft() for _ in range(self.program.channels[ch].tokens_out)]
            task_state.cursor[ch] = 0
        for ch in task_state.task.channels_out:
            task_state.cursor[ch] = 0

    def body(self, task_state: TaskState) -> None:
        io = self.io
        if io is not None:  # EL_DEBUG_TASK_BEGIN
            if io.armed:
                self.serve(io.task_begin, task_state.task.id)
            else:
                io.task_begin(task_state.task.id)
        for kind, ident in task_state.task.runs:
            if kind == "dataflow":
                self.dataflows[ident].run()
            else:
                self.charts[ident].run()
        if io is not None:
            io.task_end()

    def publish(self, task_state: TaskState) -> None:
        """The task's outputs, channel tokens and chart activity become
        visible (device ``write()`` does nothing on a simulated board)."""
        task = task_state.task
        for item in task.writes:
            self.published[item] = list(task_state.local[item])
        for ch in task.channels_out:
            self.channels[ch].extend(task_state.staging[ch][:self.program.channels[ch].tokens_in])
        for chart in self.charts_of_task[task.id]:
            self.charts[chart].publish()

    def boot(self) -> None:
        for actor in self.actors:
            actor.start()

    def shutdown(self) -> None:
        for actor in self.actors:
            actor.stop()


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
                state.published[new.id] = list(values)
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


def _transfer(old: ProgramState, new: ProgramState, report: Replacement) -> None:
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
            new.published[item.id] = list(old.published[previous.id])
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
    step times and activity; another restarts at its initial step."""
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
            report.kept_charts.append(runner.chart.name)
        elif previous is not None:
            report.restarted_charts.append(runner.chart.name)


def _transfer_channels(old: ProgramState, new: ProgramState) -> None:
    old_channels = {c.name: (c, old.channels[c.id]) for c in old.program.channels}
    for ch in new.program.channels:
        if ch.name in old_channels and old_channels[ch.name][0].type == ch.type:
            new.channels[ch.id] = deque(old_channels[ch.name][1])


def _carry(old: ProgramState, task_state: TaskState) -> CarriedPublication:
    """A released, unpublished activation of the old program, to deliver."""
    program, task = old.program, task_state.task
    due = task_state.released_at_us + task.deadline * program.tick_us
    items = {program.items[i].name: (program.items[i], list(task_state.local[i])) for i in task.writes}
    channels = {program.channels[c].name: (program.channels[c].type,
                                           task_state.staging[c][:program.channels[c].tokens_in])
                for c in task.channels_out}
    charts = {}
    for cid in old.charts_of_task[task.id]:
        runner = old.charts[cid]
        charts[runner.chart.name] = {s.name for s in runner.chart.steps if runner.slots[s.slot] == s.id}
    return CarriedPublication(due, task.name, items, channels, charts)


# ====================================================================== clocks


class Clock:
    """Virtual time (``pace`` None: instants follow each other at once) or
    paced real time: logical time runs ``pace`` times as fast as
    ``time.monotonic`` (1 = real time), anchored at the first instant.
    ``stop()`` (e.g. from a signal handler) ends waiting."""

    def __init__(self, pace: float | None = None):
        self.pace = pace
        self.stopped = False
        self._start: float | None = None
        self._first_us = 0

    def stop(self) -> None:
        self.stopped = True

    def wait_until(self, time_us: int, idle: Callable[[float], None] | None = None) -> bool:
        """Wait for logical time ``time_us``; False when stopped. ``idle(s)``
        waits at most s seconds (serving the interfaces' links)."""
        if self.pace is None:
            return not self.stopped
        while not self.stopped:
            left = self.remaining_s(time_us)
            if left <= 0:
                break
            (idle or time.sleep)(min(left, 0.05))
        return not self.stopped

    def remaining_s(self, time_us: int) -> float:
        """Real seconds until logical time ``time_us`` is due (the first
        time asked for is due at once: it anchors the clock)."""
        if self._start is None:
            self._start, self._first_us = time.monotonic(), time_us
        return self._start + (time_us - self._first_us) / 1e6 / self.pace - time.monotonic()

    def resync(self, time_us: int) -> None:
        """Logical time ``time_us`` is due now: after a halt, real time
        resumes from here instead of catching up."""
        if self.pace is not None:
            self._start, self._first_us = time.monotonic(), time_us

    def late_us(self, time_us: int) -> int:
        """How far (logical µs) real time is past ``time_us``."""
        if self.pace is None or self._start is None:
            return 0
        return int((time.monotonic() - self._start) * 1e6 * self.pace) - (time_us - self._first_us)


# ====================================================================== the engine


@dataclass
class InterfaceOptions:
    """What the interpreter serves (the host board's options): ``debug``
    ``pty:LINK`` or ``tcp:PORT`` (``,halt`` to start halted), ``modbus_tcp``
    a port, ``modbus_rtu`` ``pty:LINK``, ``nvram`` the file of persistent
    params (None: in memory); ``maps`` a folder for debug_map.json and
    service_map.* (rewritten at each replacement); ``model`` and
    ``schedule`` read a model sent over the debug link (its imports are
    relative to ``model``)."""

    debug: str | None = None
    modbus_tcp: str | None = None
    modbus_rtu: str | None = None
    nvram: str | None = None
    maps: Path | None = None
    model: Path | None = None
    schedule: str | None = None


class InterfaceError(Exception):
    """A link of the interfaces that cannot be opened (the library printed
    why on stderr)."""


class Engine:
    """Runs a program: boot, the dispatch table instant after instant,
    shutdown; and live replacement (:meth:`replace_model`).

    ``stimulus`` feeds device data (and, if it has such columns, params and
    vars); ``trace`` records every instant. ``on_replace`` is called with a
    :class:`Replacement` after every swap. With ``interfaces`` each program
    runs with its interfaces library (interfaces.py): the debug and service
    interfaces are served, and a model sent over the debug link replaces
    the program; ``say`` prints what the run reports (a refused model)."""

    def __init__(self, program: Program, plugin_cache: PluginCache | None = None,
                 stimulus: Stimulus | None = None, trace: TraceWriter | None = None,
                 on_replace: Callable[[Replacement], None] | None = None,
                 interfaces: InterfaceOptions | None = None, say: Callable[[str], None] | None = None):
        self.cache = plugin_cache or PluginCache()
        self.interfaces = interfaces
        self.say = say or (lambda text: None)
        self._load_results: queue.Queue = queue.Queue()  # from the thread checking a sent model
        self._loading = False  # a model sent over the debug link is being checked or swapped in
        self.state = self._prepare(program)
        self.stimulus = stimulus
        self.trace = trace
        self.on_replace = on_replace
        self.sampler = Sampler(trace.columns if trace else columns_of(program))
        self.sampler.bind(program, self.state.published, self.state.charts)
        self.clock = Clock()
        self.activations: dict[str, int] = {}
        self.overruns: dict[str, int] = {}
        self.last_time_us: int | None = None
        self.carried: list[CarriedPublication] = []
        self._armed: ProgramState | None = None  # the next program, swapped in at the next instant
        self._armed_lock = threading.Lock()
        self._base = 0  # the current hyperperiod's first tick
        self._index = 0  # the next instant in the table
        self._booted = False

    @property
    def program(self) -> Program:
        return self.state.program

    def _prepare(self, program: Program) -> ProgramState:
        plugins = self.cache.load_all(program.specs)
        io = None
        if self.interfaces is not None:
            io = Interfaces(Library(program, self.cache))
            if self.interfaces.debug is not None and not io.has_debug:
                raise PluginError(f"model '{program.name}' has no debug interface, which this run serves "
                                  "(declare one: `debug on uart0`)")
        return ProgramState(program, plugins, self.cache.batch_runner, io)

    @property
    def io(self) -> Interfaces | None:
        """The running program's interfaces library (None without --debug,
        --modbus-*)."""
        return self.state.io

    def _open_interfaces(self, state: ProgramState) -> None:
        """Open (or adopt) the links, take what persistent storage holds,
        and write the maps."""
        o = self.interfaces
        if not state.io.open(o.debug, o.modbus_tcp, o.modbus_rtu, o.nvram):
            raise InterfaceError("the debug or service interface cannot be opened")
        state.io.pull(state.published)
        if o.maps is not None:
            o.maps.mkdir(parents=True, exist_ok=True)
            for name, path in state.io.library.files.items():
                if name.endswith((".json", ".csv", ".md")):
                    shutil.copyfile(path, o.maps / name)

    def serve_interfaces(self, call: Callable, *args) -> None:
        """A call into the interfaces library (see ProgramState.serve), then
        what it asked for: a model to check, a clock to resynchronise."""
        state, io = self.state, self.state.io
        while not self._load_results.empty():
            io.load_result(*self._load_results.get())
        state.serve(call, *args)
        if io.take_resync():
            self.clock.resync(self.next_time_us())
        text = io.take_load()
        if text is not None:
            self._loading = True
            threading.Thread(target=self._check_sent_model, args=(text,), name="easylab-load", daemon=True).start()

    def _check_sent_model(self, text: bytes) -> None:
        """Front end and build of a model sent over the debug link; a good
        one is swapped in at the next instant, a bad one is refused."""
        from ..frontend import lower_file

        running = f"program 0x{self.program.program_id:08x} runs on"
        path = self.interfaces.model or Path(self.program.source)
        try:
            program, result = lower_file(path, self.interfaces.schedule, text=text.decode("utf-8"))
        except (UnicodeDecodeError, OSError, ValueError) as err:
            program, result = None, None
            message = f"{path}: {err}"
        if program is None:
            if result is not None:
                first = result.diagnostics.sorted()
                message = first[0].render(result.sources).splitlines()[0] if first else "refused"
            self.say(f"easylab run: a model sent by the debugger was refused: {message}; {running}")
            self._load_results.put((LOAD_REFUSED, 0, message))
            self._loading = False
            return
        if self.is_running(program):  # nothing to replace
            self._load_results.put((LOAD_REPLACED, program.program_id, "unchanged: the running program"))
            self._loading = False
            return
        try:
            self.replace_model(program)
        except PluginError as err:
            self.say(f"easylab run: a model sent by the debugger was refused: {err}; {running}")
            self._load_results.put((LOAD_REFUSED, 0, str(err).splitlines()[0]))
            self._loading = False

    # ------------------------------------------------------------ running

    def boot(self) -> None:
        """Open and start devices (nothing to do when simulated), then the
        actors' ``start`` code, in instance order."""
        if not self._booted:
            self._booted = True
            self.state.boot()
            if self.state.io is not None:
                self._open_interfaces(self.state)

    def shutdown(self) -> None:
        """Actors' ``stop`` code, then close the trace (ending the VCD after
        the last traced tick)."""
        if self._booted:
            self._booted = False
            self.state.shutdown()
            if self.state.io is not None:
                self.state.io.close()
        if self.trace is not None:
            end = None if self.last_time_us is None else self.last_time_us + self.program.tick_us
            self.trace.close(end)

    def next_time_us(self) -> int:
        """The logical time of the next instant to process."""
        t = self._instant_time_us()
        if self.carried:
            t = min(t, self.carried[0].due_us)
        return t

    def run(self, duration_us: int | None = None, clock: Clock | None = None,
            instants: int | None = None) -> None:
        """Process instants until logical time ``duration_us`` (that instant
        excluded, as the host board does), ``instants`` instants, or until
        the clock is stopped. Boots first if needed; does not shut down."""
        self.boot()
        if clock is not None:
            self.clock = clock
        done = 0
        while instants is None or done < instants:
            t = self.next_time_us()
            if duration_us is not None and t >= duration_us:
                self._wait(duration_us)  # a real-time run lasts its duration
                break
            if not self._wait(t):
                break
            self.step()
            done += 1

    def _wait(self, time_us: int) -> bool:
        """Wait for logical time ``time_us`` (the interfaces served meanwhile,
        at least once per instant); False when the clock was stopped."""
        io = self.state.io
        if io is None:
            return self.clock.wait_until(time_us)
        if self.clock.pace is None:  # virtual time: answer what is there, never wait
            self.serve_interfaces(io.idle, 0)
            return not self.clock.stopped

        def idle(seconds: float) -> None:
            if seconds >= 0.001:
                self.serve_interfaces(io.idle, int(seconds * 1000))
            else:  # below poll()'s millisecond: look, then sleep the rest
                self.serve_interfaces(io.idle, 0)
                time.sleep(max(0.0, seconds))
        if self.clock.remaining_s(time_us) <= 0:
            self.serve_interfaces(io.idle, 0)
        return self.clock.wait_until(time_us, idle)

    def step(self) -> None:
        """One instant (docs/ir.md): publish, inputs, device reads, release,
        trace, task bodies; a pending replacement swaps in after publishing."""
        t = self.next_time_us()
        state = self.state
        while self.carried and self.carried[0].due_us <= t:
            self.carried.pop(0).deliver(state)
        instant = self._instant_at(t)
        if instant is not None:
            for task_id in instant.publish:
                task_state = state.tasks[task_id]
                if task_state.pending:
                    state.publish(task_state)
                    task_state.pending = False
        if self._armed is not None:
            with self._armed_lock:
                new, self._armed = self._armed, None
            self._swap(t, new)
            state = self.state
            instant = self._instant_at(t)
        if instant is None:  # a time only a carried publication had
            self._record(t)
            return
        if self.stimulus is not None:
            self.stimulus.apply_inputs(t, state.published)
        if state.io is not None:  # EL_DEBUG_INSTANT: queued writes apply; halts at an instant
            state.io.set_tick(t // self.program.tick_us)
            self.serve_interfaces(state.io.instant)
            state = self.state
        released = instant.release
        if released:
            if self.stimulus is not None:
                for device, readers in state.readers:
                    if not readers.isdisjoint(released):
                        self.stimulus.read_device(device, t, state.published)
            for task_id in released:
                task_state = state.tasks[task_id]
                state.release(task_state)
                task_state.released_at_us = t
                name = task_state.task.name
                self.activations[name] = self.activations.get(name, 0) + 1
        self._record(t)
        for task_id in released:
            task_state = state.tasks[task_id]
            state.body(task_state)
            task_state.pending = True
            if self.clock.late_us(t) > task_state.task.deadline * self.program.tick_us:
                self.overruns[task_state.task.name] = self.overruns.get(task_state.task.name, 0) + 1
        self._advance()

    def _record(self, t: int) -> None:
        self.last_time_us = t
        if self.trace is not None:
            self.trace.record(t, self.sampler.snapshot())

    # ------------------------------------------------------------ the table

    def _instant_time_us(self) -> int:
        return (self._base + self.state.instants[self._index].tick) * self.program.tick_us

    def _instant_at(self, t: int) -> Instant | None:
        return self.state.instants[self._index] if self._instant_time_us() == t else None

    def _advance(self) -> None:
        self._index += 1
        if self._index == len(self.state.instants):
            self._index = 0
            self._base += self.program.hyperperiod

    def _position(self, t: int) -> None:
        """Point at the program's first instant at or after time ``t``."""
        tick_us, hyper = self.program.tick_us, self.program.hyperperiod
        tick = -(-t // tick_us)
        self._base = tick // hyper * hyper
        ticks = [i.tick for i in self.state.instants]
        self._index = next((k for k, x in enumerate(ticks) if self._base + x >= tick), None)
        if self._index is None:
            self._base += hyper
            self._index = 0

    # ------------------------------------------------------------ replacement

    def is_running(self, program: Program) -> bool:
        """Whether ``program`` is the running one: the same IR (program id)
        and the same actor code (plug-in digests)."""
        from .plugins import plugin_source

        running = self.state
        if program.program_id != running.program.program_id:
            return False
        try:
            digests = [self.cache.digest(plugin_source(s)) for s in program.specs]
        except (OSError, ValueError):
            return False
        return digests == [p.digest for p in running.plugins]

    def replace_model(self, new_program: Program) -> None:
        """Swap in ``new_program`` at the next instant.

        Its plug-ins are built and loaded now (a PluginError leaves the
        running program untouched); the swap itself happens in the next
        :meth:`step`, after that instant's publications, so no activation's
        outputs are lost. Safe to call from another thread than the one
        running the engine; a later call before the swap supersedes this one.
        """
        prepared = self._prepare(new_program)
        with self._armed_lock:
            self._armed = prepared

    def _swap(self, t: int, new: ProgramState) -> None:
        old = self.state
        report = Replacement(t, old.program.program_id, new.program.program_id)
        if old.io is not None:  # the links move to the new library: clients stay connected
            old.io.handover()
            old.io.close()
            self._open_interfaces(new)
            if self._loading:
                new.io.load_result(LOAD_REPLACED, new.program.program_id)
                self._loading = False
        for task_state in old.tasks:
            if task_state.pending:
                self.carried.append(_carry(old, task_state))
                report.carried_tasks.append(task_state.task.name)
        self.carried.sort(key=lambda c: c.due_us)
        _transfer(old, new, report)
        self.state = new
        self._position(t)
        if self.stimulus is not None:
            self.stimulus.bind(new.program)
            report.ignored_stimulus = list(self.stimulus.unbound)
        report.frozen = self.sampler.bind(new.program, new.published, new.charts)
        traced = {c.name for c in self.sampler.columns}
        report.untraced = [i.name for i in new.program.items if i.name not in traced] + \
                          [c.name for c in new.program.charts if c.name not in traced]
        if self.on_replace is not None:
            self.on_replace(report)
