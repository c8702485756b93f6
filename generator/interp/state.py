"""One program at run time: the published items, each task's local copies,
channels, actor instances, dataflows and charts (docs/local.md), and what
a task does at its release, in its body and at its deadline.

Everything the dispatcher moves lives in C memory at fixed addresses (items
and copies as ctypes arrays, channels as rings, each task's staging arrays
and flags), so that the dispatch table becomes plans of the runner
(runner.py) once: per instant, the publications, the releases and, where
no Python is needed, the bodies. :class:`ProgramState` runs an instant's
parts for the engine's step (with the stimulus, the interfaces, the trace
and the charts in between) and whole stretches of instants in one call of
the runner when nothing in Python has to happen (:meth:`run_native`).

With a multi-core plan (``easylab run --cores N``, docs/multicore.md) the
parallel dataflows run each activation as one job of the runner on the
plan's cores, and the bodies of tasks released together that need no
Python run as one job, each task on its core.
"""

from __future__ import annotations

import ctypes
from typing import Callable

from ..core import expr as I
from ..ir.multicore import MulticorePlan, TaskGroup
from ..ir.program import Instant, Program, Task
from . import runner as R
from . import values as V
from .charts import ChartRunner
from .dataflow import ActorState, DataflowRunner
from .devices import ModelDevices
from .interfaces import PROBE, Interfaces
from .plugins import Plugin


# ====================================================================== one program


class TaskState:
    """A task's local copies (by item id, C arrays; None for items it does
    not use), its channels' staging arrays, and in C memory whether an
    activation waits for its deadline, how many it had and when the last
    was released."""

    def __init__(self, task: Task, program: Program, published: list):
        self.task = task
        self.local: list[ctypes.Array | None] = [None] * len(program.items)
        for item in dict.fromkeys(task.reads + task.writes):
            self.local[item] = type(published[item]).from_buffer_copy(published[item])
        self.staging: dict[int, R.Stage] = {}
        for ch in task.channels_in:
            self.staging[ch] = R.Stage(program.channels[ch].type, program.channels[ch].tokens_out)
        for ch in task.channels_out:
            self.staging[ch] = R.Stage(program.channels[ch].type, program.channels[ch].tokens_in)
        self._pending = ctypes.c_uint8(0)
        self._count = ctypes.c_uint64(0)
        self._released_at = ctypes.c_uint64(0)
        # What the runner needs: a flag, a counter, a time.
        self.pending_flag = ctypes.addressof(self._pending)
        self.counter = ctypes.addressof(self._count)
        self.release_time = ctypes.addressof(self._released_at)

    @property
    def pending(self) -> bool:
        """Released, not yet published."""
        return bool(self._pending.value)

    @pending.setter
    def pending(self, value: bool) -> None:
        self._pending.value = int(value)

    @property
    def activations(self) -> int:
        return self._count.value

    @property
    def released_at_us(self) -> int:
        return self._released_at.value


class InstantPlan:
    """What one instant of the table does, as spans of the runner: its
    publications, its releases, and its releases followed by the bodies that
    need no Python (``inline``, task ids); the tasks whose bodies need Python
    (``python``, with a chart), the chart tasks it publishes, the tasks it
    publishes that drive a device with host handlers, and whether the runner
    does all of it (``native``). ``group_bodies``: the inline bodies as one
    job on the cores, when the multi-core plan runs them so (else None)."""

    def __init__(self, instant: Instant, publish: R.Span, release: R.Span, release_bodies: R.Span,
                 inline: list[int], chart_tasks: list[int], native: bool, device_tasks: list[int],
                 group_bodies: R.Span | None = None):
        self.tick = instant.tick
        self.released = instant.release
        self.publish = publish
        self.release = release
        self.release_bodies = release_bodies
        self.inline = inline
        self.python = [t for t in instant.release if t not in inline]
        self.chart_tasks = chart_tasks
        self.device_tasks = device_tasks  # tasks whose publication a device's write() follows
        self.native = native
        self.group_bodies = group_bodies


class ProgramState:
    """The run-time state of one program, built from its IR and plug-ins
    (``plugins[spec id]``; ``runner`` runs the plans), as the firmware holds
    it at boot. ``multicore``: the plan its parallel parts follow (None:
    one core)."""

    def __init__(self, program: Program, plugins: list[Plugin], runner: R.Runner, io: Interfaces | None = None,
                 model_devices: ModelDevices | None = None, multicore: MulticorePlan | None = None):
        self.program = program
        self.plugins = plugins
        self.io = io
        self.model_devices = model_devices  # devices running host handlers from the model's folder
        self.runner = runner
        self.cursor = R.Cursor()  # the next instant of the table (the engine's position)
        # The published items: with interfaces, the library's own arrays.
        self.published: list[ctypes.Array] = list(io.items) if io is not None else \
            [(V.ctype(i.type) * i.count)() for i in program.items]
        for item, array in zip(program.items, self.published):
            array[:] = [V.literal(item.type, item.initial)] * item.count
        self.tasks = [TaskState(t, program, self.published) for t in program.tasks]
        self.channels = [R.Ring(c.type, c.capacity, [V.literal(c.type, v) for v in c.initial])
                         for c in program.channels]
        self.actors = [ActorState(inst, program.specs[inst.spec], plugins[inst.spec],
                                  io.actor_states[inst.id] if io is not None else None)
                       for inst in program.instances]
        self.dataflows: list[DataflowRunner | None] = []
        for df in program.dataflows:
            if df.task is None:  # run by no task: never runs
                self.dataflows.append(None)
                continue
            actors = {self.actors[i].instance.name: self.actors[i] for i in df.instances}
            self.dataflows.append(DataflowRunner(program, df, actors, self.tasks[df.task], runner, self.cursor))
        self.multicore = multicore
        for firing_plan in multicore.dataflows if multicore is not None else ():
            flow = self.dataflows[firing_plan.dataflow.id]
            if firing_plan.parallel and flow is not None:
                flow.parallelise(firing_plan)
        self.group_jobs: dict[tuple[int, ...], R.Job | None] = {}  # by released tasks: their job, if any
        self.charts = [ChartRunner(program, c, self.tasks[c.task] if c.task is not None else None,
                                   self.run_dataflow) for c in program.charts]
        self.readers = [(d.id, set(d.read_by)) for d in program.devices if d.read_by]
        self.charts_of_task = [[cid for kind, cid in t.runs if kind == "chart"] for t in program.tasks]
        # Per task, the devices running host handlers whose write() follows its publication.
        handled = model_devices.devices if model_devices is not None else {}
        self.writes_of_task = [[d.id for d in program.devices if d.id in handled and d.written_by == t.id]
                               for t in program.tasks]
        self.handled_readers = {t for d in program.devices if d.id in handled for t in d.read_by}
        if io is not None and io.has_debug:  # the debugger's probes where the firmware has them
            for runner_ in self.dataflows:
                if runner_ is not None:
                    runner_.probe_actor = self._probe_actor
                    runner_.armed = lambda: io.armed
            for chart in self.charts:
                chart.probe = self.probe
        self._inline = self._inline_args()
        self.table, self.instants = self._table(program.instants or [Instant(0, [], [])])  # as C: one empty instant

    # ------------------------------------------------------------ plans

    def _publish_ops(self, task: TaskState) -> list[R.Op]:
        """At the deadline, if released: the written items, the channels'
        tokens (the charts' activity is Python's)."""
        ops = [R.copy(ctypes.addressof(self.published[i]), self.program.items[i].type,
                      ctypes.addressof(task.local[i]), self.program.items[i].type, self.program.items[i].count)
               for i in task.task.writes]
        ops += [R.push(self.channels[ch], task.staging[ch]) for ch in task.task.channels_out]
        return [R.publish(task.pending_flag, len(ops))] + ops

    def _release_ops(self, task: TaskState) -> list[R.Op]:
        """At the release: latch the items, take the channels' tokens."""
        ops = [R.copy(ctypes.addressof(task.local[i]), self.program.items[i].type,
                      ctypes.addressof(self.published[i]), self.program.items[i].type, self.program.items[i].count)
               for i in task.task.reads]
        ops += [R.take(self.channels[ch], task.staging[ch]) for ch in task.task.channels_in]
        ops += [R.rewind(task.staging[ch]) for ch in task.task.channels_out]
        return ops + [R.release(task.counter, task.release_time)]

    def _inline_args(self) -> dict[int, list]:
        """The tasks whose bodies the runner runs itself (``inline``), with
        the run-time arguments of their dataflows: tasks that run only
        dataflows whose arguments read only items no task writes (params).
        Those change only by inputs (stimulus, interfaces), before the
        releases that latch them, so the arguments can be evaluated on the
        published values once the inputs are in: before the releases of an
        instant, or once for a stretch of instants without inputs."""
        written = {i for t in self.program.tasks for i in t.writes}
        constant: dict[int, list] = {}
        for task in self.program.tasks:
            evaluators = []
            for kind, ident in task.runs:
                runner_ = self.dataflows[ident] if kind == "dataflow" else None
                if runner_ is None:
                    break
                if any(_reads(a, written) for a in runner_.actors.values()):
                    break
                evaluators += runner_.param_evaluators
            else:
                constant[task.id] = evaluators
        return constant

    def _table(self, instants: list[Instant]) -> tuple[R.Table, list[InstantPlan]]:
        publish = [self._publish_ops(t) for t in self.tasks]
        release = [self._release_ops(t) for t in self.tasks]
        body = {}
        for task_id in self._inline:
            task = self.tasks[task_id]
            body[task_id] = [R.call(self.dataflows[ident].plan) for _, ident in task.task.runs] + \
                            [R.pending(task.pending_flag)]
        rows = []  # per instant: its publications, releases and inline bodies, and the inline tasks
        grouped = []  # per instant: its inline bodies are one job
        for instant in instants:
            inline = [t for t in instant.release if t in body]
            job = self._group_job(instant, inline)
            bodies = [op for t in inline for op in body[t]] if job is None else \
                [R.parallel(job)] + [R.pending(self.tasks[t].pending_flag) for t in inline]
            rows.append(([op for t in instant.publish for op in publish[t]],
                         [op for t in instant.release for op in release[t]], bodies, inline))
            grouped.append(job is not None)
        charts = [[t for t in instant.publish if self.charts_of_task[t]] for instant in instants]
        # Python's too: the deadlines and releases with a device running host handlers.
        devices = [[t for t in instant.publish if self.writes_of_task[t]] for instant in instants]
        native = [not c and not d and self.handled_readers.isdisjoint(i.release) and len(row[3]) == len(i.release)
                  for i, c, d, row in zip(instants, charts, devices, rows)]
        table = R.Table([p + r + b for p, r, b, _ in rows], [i.tick for i in instants], native,
                        self.program.hyperperiod, self.program.tick_us)
        plans = [InstantPlan(instant, table.span(k, 0, len(p)), table.span(k, len(p), len(r)),
                             table.span(k, len(p), len(r) + len(b)), inline, charts[k], native[k], devices[k],
                             table.span(k, len(p) + len(r), len(b)) if grouped[k] else None)
                 for k, (instant, (p, r, b, inline)) in enumerate(zip(instants, rows))]
        return table, plans

    def _group_job(self, instant: Instant, inline: list[int]) -> R.Job | None:
        """The job running the bodies of tasks released together, each on
        its core of the plan (its dataflows in their single-core order):
        None unless the plan runs the group in parallel and its tasks that
        need no Python use two cores or more (charts run in Python)."""
        key = tuple(sorted(instant.release))
        if key not in self.group_jobs:
            group = next((g for g in self.multicore.groups if tuple(g.tasks) == key), None) \
                if self.multicore is not None else None
            self.group_jobs[key] = self._make_group_job(group, inline) if group is not None else None
        return self.group_jobs[key]

    def _make_group_job(self, group: TaskGroup, inline: list[int]) -> R.Job | None:
        if not group.parallel or len({group.core[t] for t in inline}) < 2:
            return None
        job = R.Job(self.multicore.cores)
        lists: list[list[R.Op]] = [[] for _ in range(self.multicore.cores)]
        for t in inline:
            lists[group.core[t]] += [op for _, ident in self.tasks[t].task.runs
                                     for op in self.dataflows[ident].sequential_ops()]
        job.set_lists(lists)
        return job

    # ------------------------------------------------------------ running

    def fault(self, err: R.RunnerFault) -> RuntimeError:
        """A runner's fault in the program's words."""
        for ch, ring in zip(self.program.channels, self.channels):
            if err.at == ring.address:
                what = "is full" if err.kind == R.RING_FULL else "has too few tokens"
                return RuntimeError(f"channel '{ch.name}' {what} ({ch.location})")
        for task in self.tasks:
            for ch, stage in task.staging.items():
                if err.at == stage.address:
                    return RuntimeError(f"channel '{self.program.channels[ch].name}': task '{task.task.name}' "
                                        f"moves more tokens than an activation has")
        return RuntimeError(f"the interpreter's runner stopped (fault {err.kind})")

    def run_ops(self, span: R.Span) -> None:
        try:
            self.runner.run(span, self.cursor)
        except R.RunnerFault as err:
            raise self.fault(err) from None

    def run_native(self, before_us: int, instants: int, ops: int) -> int:
        """Instants from the cursor on, in one call of the runner, as long
        as they need no Python (none with a chart), are before ``before_us``
        and at most ``instants`` (see Runner.run_instants). The run-time
        arguments, constant over such a stretch, are evaluated first."""
        published = self.published
        for evaluators in self._inline.values():
            for cell, evaluate in evaluators:
                cell[0] = evaluate(published, None, None)
        try:
            return self.runner.run_instants(self.table, self.cursor, before_us, instants, ops)
        except R.RunnerFault as err:
            raise self.fault(err) from None

    def serve(self, call: Callable, *args) -> None:
        """Call into the interfaces library (which may serve clients): the
        charts' slots go in before (the items are the library's)."""
        io = self.io
        io.push(self.published, self.charts, self.model_devices)
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

    def publish(self, plan: InstantPlan) -> None:
        """The deadlines of an instant: the released tasks' outputs, channel
        tokens and chart activity become visible, then ``write()`` of the
        devices they drive (which does nothing on a simulated device)."""
        charts = [t for t in plan.chart_tasks if self.tasks[t].pending]
        devices = [t for t in plan.device_tasks if self.tasks[t].pending]
        self.run_ops(plan.publish)
        for task in charts:
            for chart in self.charts_of_task[task]:
                self.charts[chart].publish()
        for task in devices:
            for device in self.writes_of_task[task]:
                self.model_devices.write(device, self.published)

    def release(self, plan: InstantPlan, time_us: int, bodies: bool = False) -> None:
        """The releases of an instant: latch the tasks' items, take their
        channel tokens; with ``bodies``, then run the bodies that need no
        Python (``plan.inline``; their run-time arguments are evaluated on
        the published params, which the releases latch)."""
        self.cursor.now_us = time_us
        if bodies and plan.inline:
            published = self.published
            for task in plan.inline:
                for cell, evaluate in self._inline[task]:
                    cell[0] = evaluate(published, None, None)
            self.run_ops(plan.release_bodies)
        else:
            self.run_ops(plan.release)

    def group_bodies(self, plan: InstantPlan) -> None:
        """The inline bodies of an instant as one job on the cores (after
        its releases): for runs that take the bodies one by one (real time),
        where tasks released together still run at once."""
        published = self.published
        for task in plan.inline:
            for cell, evaluate in self._inline[task]:
                cell[0] = evaluate(published, None, None)
        self.run_ops(plan.group_bodies)

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
        task_state.pending = True

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



def _reads(actor: ActorState, items: set[int]) -> bool:
    """Whether an actor's run-time arguments read one of ``items``."""
    return any(r.kind == "item" and r.target in items
               for e in actor.instance.runtime_args.values() for r in I.refs(e))
