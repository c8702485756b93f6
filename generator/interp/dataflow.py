"""Dataflows: one iteration of the IR's static schedule per activation
(docs/ir.md, "Dataflows"), actors fired through their plug-ins.

Buffers are laid out per iteration: an edge with ``d`` initial tokens whose
producer fires ``r`` times per iteration holds ``d + r·prod`` tokens; the
k-th firing of the producer writes at ``d + k·prod``, the j-th firing of the
consumer reads at ``j·cons``, and at the end of the iteration the ``d``
newest tokens move to the front. This is the C backend's linear layout with
the whole iteration as one loop body; it is valid for every admissible
schedule, and since token values do not depend on the schedule (SDF
determinacy) the values are the firmware's whatever layout it chose. With
the layout static, every firing's and every external node's token
addresses are computed once: an activation is one plan of the runner
(runner.py), in the schedule's order.

This layout gives every token of an iteration its own place, so it is
also the host board's layout for a parallel dataflow: on several cores
(``easylab run --cores N``, docs/multicore.md) the same firings' operations
run as one job of the runner, each core's list in the order of the IR's
multi-core plan, with a wait before a firing for the latest firing it
follows on each other core.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass, field
from typing import Callable

from ..ir.multicore import FiringPlan
from ..ir.program import ActorInstance, ActorSpec, Buffer, Dataflow, Program
from . import runner as R
from . import values as V
from .exprs import Evaluator, ExprCompiler
from .plugins import Plugin


class ActorState:
    """One actor instance: its plug-in, its state and its run-time
    parameters' cells (what ``el_plugin_step`` receives)."""

    def __init__(self, instance: ActorInstance, spec: ActorSpec, plugin: Plugin,
                 memory: tuple[int, int] | None = None):
        self.instance = instance
        self.spec = spec
        self.plugin = plugin
        if memory is not None:  # (address, size): the state in the interfaces library, zero at load
            address, size = memory
            if size != plugin.state_size:
                raise ValueError(f"actor {instance.name}: its state has {size} bytes in the interfaces library, "
                                 f"{plugin.state_size} in its plug-in")
            self.state = (ctypes.c_uint8 * max(1, size)).from_address(address)
        else:
            words = max(1, (plugin.state_size + 7) // 8)  # 8-byte aligned, zeroed as static C storage
            self.state = (ctypes.c_uint64 * words)()
        self.state_address = ctypes.addressof(self.state)
        self.param_cells = [(V.ctype(t) * 1)() for t in spec.runtime_params.values()]
        self.params = (ctypes.c_void_p * max(1, len(self.param_cells)))(
            *(ctypes.addressof(c) for c in self.param_cells))
        compiler = ExprCompiler()
        self.param_evaluators: list[tuple[ctypes.Array, Evaluator]] = [
            (cell, compiler.compile(instance.runtime_args[name], t))
            for cell, (name, t) in zip(self.param_cells, spec.runtime_params.items())]
        self.scratch: dict[str, ctypes.Array] = {}  # outputs that feed no edge

    def start(self) -> None:
        self.plugin.start(self.state_address)

    def stop(self) -> None:
        self.plugin.stop(self.state_address)

    def take_state_from(self, other: "ActorState") -> None:
        """Carry another instance's state over (same plug-in: same layout)."""
        ctypes.memmove(self.state, other.state, self.plugin.state_size)


@dataclass
class EdgeBuffer:
    """The tokens of one edge for one iteration (see the module docstring)."""

    buffer: Buffer
    delay: int
    per_iteration: int  # tokens produced (and consumed) per iteration
    array: ctypes.Array = field(init=False)
    size: int = field(init=False)  # bytes per token

    def __post_init__(self) -> None:
        ctype = V.ctype(self.buffer.type)
        self.array = (ctype * (self.delay + self.per_iteration))(
            *(V.literal(self.buffer.type, v) for v in self.buffer.initial))
        self.size = ctypes.sizeof(ctype)

    def address(self, token: int) -> int:
        return ctypes.addressof(self.array) + token * self.size

    def write_at(self, k: int) -> int:
        """First token written by the producer's k-th firing."""
        return self.delay + k * self.buffer.prod

    def read_at(self, j: int) -> int:
        """First token read by the consumer's j-th firing."""
        return j * self.buffer.cons

    def delay_tokens(self) -> list:
        return self.array[:self.delay]

    def set_delay_tokens(self, tokens: list) -> None:
        self.array[:self.delay] = tokens


class DataflowRunner:
    """Runs one dataflow of a task: the schedule unrolled into one plan of
    the runner (firings, the edges' copies, external nodes moving values
    between edges and the task's copies and staging arrays), run in one
    call per activation. ``task`` is the owning task's
    :class:`~easylab.interp.state.TaskState`.
    """

    def __init__(self, program: Program, dataflow: Dataflow, actors: dict[str, ActorState], task,
                 runner: R.Runner, cursor: R.Cursor):
        self.dataflow = dataflow
        self.actors = actors
        self.task = task
        reps = dataflow.repetitions
        self.buffers = [EdgeBuffer(b, len(b.initial), reps[b.src] * b.prod) for b in dataflow.buffers]
        self._program = program
        self._runner = runner
        self._cursor = cursor
        externals = {e.node: e for e in dataflow.externals}
        # The debugger's probe before each firing, while it is armed: then
        # the plan runs one operation per call.
        self.probe_actor: Callable[[int], None] | None = None
        self.armed: Callable[[], bool] = lambda: False
        self._ops: list[R.Op] = []
        self._firing: list[int | None] = []  # per operation: the instance it fires, if it is a firing
        self._keep: list = []  # pointer arrays and scratch outputs the plan refers to
        fired: dict[str, int] = {}
        self._firing_ops: list[list[R.Op]] = []  # per firing of one iteration (schedule order): its operations
        for node in dataflow.schedule.firings():
            k = fired.get(node, 0)
            fired[node] = k + 1
            first = len(self._ops)
            if node in externals:
                self._external(externals[node], k)
            else:
                self._actor(actors[node], k)
            self._firing_ops.append(self._ops[first:])
        self._rotate = [R.copy(edge.address(0), edge.buffer.type, edge.address(edge.per_iteration),
                               edge.buffer.type, edge.delay)
                        for edge in self.buffers if edge.delay]  # the delay tokens move to the front
        for op in self._rotate:
            self._add(op)
        self.sequential = R.OpList(self._ops)  # one core, in schedule order
        self.plan = self.sequential  # what an activation runs
        self.job: R.Job | None = None
        self._singles: list[R.Span] | None = None  # the plan one operation at a time (for the probes)
        self.param_evaluators = [pe for a in actors.values() for pe in a.param_evaluators]

    def run(self) -> None:
        """One activation: the run-time arguments from the task's copies,
        then every firing of one iteration."""
        local = self.task.local
        for cell, evaluate in self.param_evaluators:
            cell[0] = evaluate(local, None, None)
        if self.armed():
            if self._singles is None:
                self._singles = [self.sequential.span(k, 1) for k in range(self.sequential.count)]
            for single, instance in zip(self._singles, self._firing):  # on one core
                if instance is not None:
                    self.probe_actor(instance)
                self._runner.run(single, self._cursor)
        else:
            self._runner.run(self.plan.all, self._cursor)

    def sequential_ops(self) -> list[R.Op]:
        """One iteration on one core, as operations (for a task group's job)."""
        return [op for ops in self._firing_ops for op in ops] + self._rotate

    def parallelise(self, plan: FiringPlan) -> None:
        """Run each activation on ``plan``'s cores (its firings are this
        dataflow's, in the same schedule order): one job of the runner,
        then the delay tokens' move on the calling thread."""
        assert len(plan.firings) == len(self._firing_ops)
        job, flags = R.Job(plan.cores), R.Flags(len(plan.firings))
        waits_before: dict[int, list[int]] = {}
        for waiting, waited in plan.cross_waits():
            waits_before.setdefault(waiting, []).append(waited)
        signalled = {waited for _, waited in plan.cross_waits()}
        lists = []
        for firings in plan.order:
            ops: list[R.Op] = []
            for f in firings:
                ops += [R.wait(flags[g], job) for g in waits_before.get(f, ())]
                ops += self._firing_ops[f]
                if f in signalled:
                    ops.append(R.signal(flags[f], job))
            lists.append(ops)
        job.set_lists(lists)
        self.job = job
        self._keep.append(flags)
        self.plan = R.OpList([R.parallel(job)] + self._rotate)

    # ------------------------------------------------------------ plan

    def _add(self, op: R.Op, instance: int | None = None) -> None:
        self._ops.append(op)
        self._firing.append(instance)

    def _edges_from(self, node: str, port: str | None) -> list[EdgeBuffer]:
        return [e for e in self.buffers if e.buffer.src == node and e.buffer.src_port == port]

    def _edge_into(self, node: str, port: str | None) -> EdgeBuffer:
        return next(e for e in self.buffers if e.buffer.dst == node and e.buffer.dst_port == port)

    def _pointers(self, addresses: list[int]) -> int:
        array = (ctypes.c_void_p * max(1, len(addresses)))(*addresses)
        self._keep.append(array)
        return ctypes.addressof(array)

    def _actor(self, actor: ActorState, k: int) -> None:
        node = actor.instance.name
        inputs, outputs, copies = [], [], []
        for port in actor.spec.ports:
            if port.direction == "in":
                edge = self._edge_into(node, port.name)  # of the port's type
                inputs.append(edge.address(edge.read_at(k)))
                continue
            # The actor writes into an edge of its port's type, else into
            # scratch room; every other edge of the port gets a copy.
            edges = self._edges_from(node, port.name)
            direct = next((e for e in edges if e.buffer.type == port.type), None)
            if direct is not None:
                out = direct.address(direct.write_at(k))
            else:
                scratch = actor.scratch.setdefault(port.name, (V.ctype(port.type) * port.rate)())
                out = ctypes.addressof(scratch)
            outputs.append(out)
            copies += [R.copy(e.address(e.write_at(k)), e.buffer.type, out, port.type, e.buffer.prod)
                       for e in edges if e is not direct]
        self._add(R.fire(actor.plugin.step_address, actor.state_address, self._pointers(inputs),
                         self._pointers(outputs), ctypes.addressof(actor.params)), actor.instance.id)
        for op in copies:
            self._add(op)

    def _external(self, ext, k: int) -> None:
        """An external node's k-th firing: items copy the task's copy (all
        its values) per firing, channels move one token per firing between
        the task's staging array and the edges."""
        task = self.task
        if ext.kind == "channel":
            stage = task.staging[ext.target]
            if ext.direction == "in":
                edges = self._edges_from(ext.node, None)
                for n, edge in enumerate(edges):
                    self._add(R.read(stage, edge.address(edge.write_at(k)), edge.buffer.type, n == len(edges) - 1))
                if not edges:
                    self._add(R.read(stage, None, stage.type, True))
            else:
                edge = self._edge_into(ext.node, None)
                self._add(R.write(stage, edge.address(edge.read_at(k)), edge.buffer.type))
            return
        item = self._program.items[ext.target]
        local = ctypes.addressof(task.local[item.id])
        if ext.direction == "in":
            for edge in self._edges_from(ext.node, None):
                self._add(R.copy(edge.address(edge.write_at(k)), edge.buffer.type, local, item.type, item.count))
        else:
            edge = self._edge_into(ext.node, None)
            self._add(R.copy(local, item.type, edge.address(edge.read_at(k)), edge.buffer.type, item.count))
