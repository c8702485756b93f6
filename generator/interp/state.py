"""One program at run time: the published items, each task's local copies,
channels, actor instances, dataflows and charts (docs/local.md), and what
a task does at its release, in its body and at its deadline."""

from __future__ import annotations

from collections import deque
from typing import Callable

from ..ir.program import Instant, Program, Task
from . import values as V
from .charts import ChartRunner
from .dataflow import ActorState, DataflowRunner
from .devices import ModelDevices
from .interfaces import PROBE, Interfaces
from .plugins import Plugin


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
                 io: Interfaces | None = None, model_devices: ModelDevices | None = None):
        self.program = program
        self.plugins = plugins
        self.io = io
        self.model_devices = model_devices  # devices running host handlers from the model's folder
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
        visible, then ``write()`` of the devices it drives (which does
        nothing on a simulated device)."""
        task = task_state.task
        for item in task.writes:
            self.published[item] = list(task_state.local[item])
        for ch in task.channels_out:
            self.channels[ch].extend(task_state.staging[ch][:self.program.channels[ch].tokens_in])
        for chart in self.charts_of_task[task.id]:
            self.charts[chart].publish()
        if self.model_devices is not None:
            for dev in self.program.devices:
                if dev.written_by == task.id:
                    self.model_devices.write(dev.id, self.published)

    def boot(self) -> None:
        """Devices' open() and start() (model.c's order), then the actors'
        start code."""
        if self.model_devices is not None:
            self.model_devices.boot(self.published)
        for actor in self.actors:
            actor.start()

    def shutdown(self) -> None:
        for actor in self.actors:
            actor.stop()
        if self.model_devices is not None:
            self.model_devices.shutdown(self.published)


