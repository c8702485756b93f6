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
the layout static, every firing's token addresses are computed once: an
activation is a short list of calls (runs of firings and copies in the C
batch runner, external nodes in Python), in the schedule's order.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass, field
from typing import Callable

from ..ir.program import ActorInstance, ActorSpec, Buffer, Dataflow, Program
from . import values as V
from .exprs import Evaluator, ExprCompiler
from .plugins import BatchOp, Plugin


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
    """Runs one dataflow of a task: the schedule unrolled into calls.

    Firings and buffer copies go to the C batch runner (``run_batch``,
    plugins.BATCH_SOURCE) in runs of consecutive operations, one call per
    run; external nodes, which move values between edges and the task's
    Python copies, are Python calls in between. The order is the
    schedule's. ``task`` is the owning task's
    :class:`~easylab.interp.engine.TaskState` (local copies, channel staging).
    """

    def __init__(self, program: Program, dataflow: Dataflow, actors: dict[str, ActorState], task,
                 run_batch: Callable[[int, int], None]):
        self.dataflow = dataflow
        self.actors = actors
        self.task = task
        reps = dataflow.repetitions
        self.buffers = [EdgeBuffer(b, len(b.initial), reps[b.src] * b.prod) for b in dataflow.buffers]
        self._program = program
        self._run_batch = run_batch
        self._externals = {e.node: e for e in dataflow.externals}
        self.calls: list[tuple[Callable, tuple]] = []
        # The same activation with the debugger's actor probe before each
        # firing, one operation per call (used while a debugger is armed).
        self.probed_calls: list[tuple[Callable, tuple]] = []
        self.probe_actor: Callable[[int], None] | None = None
        self.armed: Callable[[], bool] = lambda: False
        self._batch: list[BatchOp] = []  # C operations not yet in a call
        self._batch_actors: list[int | None] = []  # the instance id of each firing in _batch
        self._keep: list = []  # pointer and operation arrays the calls refer to
        fired: dict[str, int] = {}
        for node in dataflow.schedule.firings():
            k = fired.get(node, 0)
            fired[node] = k + 1
            if node in self._externals:
                self._external(self._externals[node], k)
            else:
                self._actor(actors[node], k)
        for edge in self.buffers:  # the delay tokens move to the front
            if edge.delay:
                self._copy(edge.address(0), edge.address(edge.per_iteration), edge.delay * edge.size)
        self._flush()
        self.param_evaluators = [pe for a in actors.values() for pe in a.param_evaluators]

    def run(self) -> None:
        """One activation: the run-time arguments from the task's copies,
        then every firing of one iteration."""
        local = self.task.local
        for cell, evaluate in self.param_evaluators:
            cell[0] = evaluate(local, None, None)
        for call, args in (self.probed_calls if self.armed() else self.calls):
            call(*args)

    def _probe(self, instance: int) -> None:
        self.probe_actor(instance)

    # ------------------------------------------------------------ plan

    def _copy(self, dst: int, src: int, size: int) -> None:
        self._batch.append(BatchOp(dst=dst, src=src, bytes=size))
        self._batch_actors.append(None)

    def _python(self, call: Callable, args: tuple) -> None:
        self._flush()
        self.calls.append((call, args))
        self.probed_calls.append((call, args))

    def _flush(self) -> None:
        """The C operations so far become one call of the batch runner (and,
        for the probed activation, one call per operation, each firing
        after its probe)."""
        if self._batch:
            ops = (BatchOp * len(self._batch))(*self._batch)
            self._keep.append(ops)
            self.calls.append((self._run_batch, (ctypes.addressof(ops), len(self._batch))))
            for k, instance in enumerate(self._batch_actors):
                if instance is not None:
                    self.probed_calls.append((self._probe, (instance,)))
                self.probed_calls.append((self._run_batch, (ctypes.addressof(ops) + k * ctypes.sizeof(BatchOp), 1)))
            self._batch = []
            self._batch_actors = []

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
                edge = self._edge_into(node, port.name)
                inputs.append(edge.address(edge.read_at(k)))
                continue
            edges = self._edges_from(node, port.name)
            if not edges:
                scratch = actor.scratch.setdefault(port.name, (V.ctype(port.type) * port.rate)())
                outputs.append(ctypes.addressof(scratch))
                continue
            first = edges[0].address(edges[0].write_at(k))
            outputs.append(first)
            # An output feeding several edges gives each edge every token.
            copies += [(e.address(e.write_at(k)), first, e.buffer.prod * e.size) for e in edges[1:]]
        self._batch.append(BatchOp(step=actor.plugin.step_address, state=actor.state_address,
                                   inputs=self._pointers(inputs), outputs=self._pointers(outputs),
                                   params=ctypes.addressof(actor.params)))
        self._batch_actors.append(actor.instance.id)
        for copy in copies:
            self._copy(*copy)

    def _external(self, ext, k: int) -> None:
        """An external node's k-th firing: items copy the task's copy (all
        its values) per firing, channels move one token per firing."""
        task = self.task
        if ext.kind == "channel":
            channel = ext.target
            if ext.direction == "in":
                edges = self._edges_from(ext.node, None)
                self._python(task.channel_to_edges, (channel, [(e.array, e.write_at(k)) for e in edges]))
            else:
                edge = self._edge_into(ext.node, None)
                self._python(task.edge_to_channel, (channel, edge.array, edge.read_at(k)))
            return
        item = ext.target
        count = self._program.items[item].count
        if ext.direction == "in":
            for edge in self._edges_from(ext.node, None):
                at = edge.write_at(k)
                self._python(task.item_to_edge, (item, edge.array, at, at + count))
        else:
            edge = self._edge_into(ext.node, None)
            at = edge.read_at(k)
            self._python(task.edge_to_item, (item, edge.array, at, at + count))
