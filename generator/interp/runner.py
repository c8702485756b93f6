"""The interpreter's plans and their C runner (``runner.c`` beside this file).

A program's run-time work is prepared once as plans: lists of operations
(:class:`Op`) on addresses that never change while the program runs (items,
task copies, edge buffers, channel rings and staging arrays, actors' state).
The runner executes a list in one call (:meth:`Runner.run`), or instant
after instant of the dispatch table while none needs Python
(:meth:`Runner.run_instants`). This module holds the operations, the
memory they work on (:class:`Ring`, :class:`Stage`, :class:`OpList`) and
the runner library, built and cached like an actor plug-in.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

from ..core import types as T
from . import values as V

SOURCE = Path(__file__).with_name("runner.c")

# Operation kinds (EL_OP_* of runner.c).
FIRE, COPY, CALL, PUSH, TAKE, REWIND, READ, WRITE, PUBLISH, PENDING, RELEASE, WIDEN, PARALLEL, WAIT, SIGNAL = \
    range(1, 16)
# Value types (EL_T_* of runner.c).
TYPES = {name: code for code, name in enumerate(
    ("bool", "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "time"))}
# Why a runner stopped early (EL_RUN_* of runner.c).
RING_FULL, RING_EMPTY, STAGE, NESTED, BAD_OP, THREADS, GAVE_UP = range(1, 8)


class Op(ctypes.Structure):
    """``el_op_t``: one operation; runner.c says which fields each kind uses."""

    _fields_ = [("kind", ctypes.c_uint16), ("src_type", ctypes.c_uint8), ("dst_type", ctypes.c_uint8),
                ("count", ctypes.c_uint32), ("fn", ctypes.c_void_p),
                ("object", ctypes.c_void_p), ("inputs", ctypes.c_void_p), ("outputs", ctypes.c_void_p),
                ("params", ctypes.c_void_p), ("dst", ctypes.c_void_p), ("src", ctypes.c_void_p)]


def fire(step: int, state: int, inputs: int, outputs: int, params: int) -> Op:
    """An actor firing: ``step(state, inputs, outputs, params)``."""
    return Op(kind=FIRE, fn=step, object=state, inputs=inputs, outputs=outputs, params=params)


def copy(dst: int, dst_type: T.ValueType, src: int, src_type: T.ValueType, count: int) -> Op:
    """``count`` values from ``src`` to ``dst``, widened as C assigns them
    (edges may widen: docs/language.md)."""
    if dst_type == src_type:
        return Op(kind=COPY, count=count * ctypes.sizeof(V.ctype(src_type)), dst=dst, src=src)
    return Op(kind=WIDEN, count=count, dst=dst, src=src, dst_type=TYPES[dst_type.name], src_type=TYPES[src_type.name])


def call(ops: "OpList") -> Op:
    """Run another list (one that calls nothing) and come back."""
    return Op(kind=CALL, count=ops.count, src=ops.address)


def push(ring: "Ring", stage: "Stage") -> Op:
    """A deadline: the stage's tokens to the end of the channel's ring."""
    return Op(kind=PUSH, object=ring.address, src=stage.address)


def take(ring: "Ring", stage: "Stage") -> Op:
    """A release: the stage filled from the front of the ring, cursor 0."""
    return Op(kind=TAKE, object=ring.address, dst=stage.address)


def rewind(stage: "Stage") -> Op:
    return Op(kind=REWIND, object=stage.address)


def read(stage: "Stage", dst: int | None, dst_type: T.ValueType, advance: bool) -> Op:
    """A channel's ``in:`` node: the token at the stage's cursor to ``dst``."""
    return Op(kind=READ, count=int(advance), object=stage.address, dst=dst, src_type=TYPES[stage.type.name],
              dst_type=TYPES[dst_type.name])


def write(stage: "Stage", src: int, src_type: T.ValueType) -> Op:
    """A channel's ``out:`` node: ``src``'s token to the stage's cursor."""
    return Op(kind=WRITE, object=stage.address, src=src, src_type=TYPES[src_type.name],
              dst_type=TYPES[stage.type.name])


def publish(flag: int, skip: int) -> Op:
    """A deadline's guard: when the task's pending flag is clear the next
    ``skip`` operations are skipped, else the flag is cleared."""
    return Op(kind=PUBLISH, count=skip, object=flag)


def pending(flag: int) -> Op:
    return Op(kind=PENDING, object=flag)


def release(counter: int, time: int) -> Op:
    """A release's bookkeeping: the task's activation counter + 1, its
    release time the instant's."""
    return Op(kind=RELEASE, object=counter, dst=time)


def parallel(job: "Job") -> Op:
    """Run ``job``'s lists on its cores; done when every core is."""
    return Op(kind=PARALLEL, object=job.address)


def wait(flag: int, job: "Job") -> Op:
    """In a job's list: wait until the firing of ``flag`` (a uint64) ran in this run of the job."""
    return Op(kind=WAIT, object=flag, src=job.address)


def signal(flag: int, job: "Job") -> Op:
    """In a job's list: the firing of ``flag`` ran in this run of the job."""
    return Op(kind=SIGNAL, object=flag, src=job.address)


class Span:
    """Operations ``address`` .. (``count`` of them) for :meth:`Runner.run`,
    with the call's arguments made once (a call converts nothing)."""

    def __init__(self, address: int, count: int):
        self.address = address
        self.count = count
        self.args = (ctypes.c_void_p(address), ctypes.c_uint32(count))


class OpList:
    """Operations in C memory, in order."""

    def __init__(self, ops: list[Op]):
        self.array = (Op * max(1, len(ops)))(*ops)
        self.count = len(ops)
        self.address = ctypes.addressof(self.array)
        self.all = Span(self.address, self.count)

    def __len__(self) -> int:
        return self.count

    def span(self, start: int, count: int) -> Span:
        """Operations ``start`` .. ``start + count``."""
        return Span(self.address + start * ctypes.sizeof(Op), count)


class _JobStruct(ctypes.Structure):
    _fields_ = [("cores", ctypes.c_uint32), ("failed", ctypes.c_uint32), ("epoch", ctypes.c_uint64),
                ("lists", ctypes.c_void_p), ("counts", ctypes.c_void_p), ("cursors", ctypes.c_void_p)]


class Job:
    """``el_job_t``: one list of operations per core, run at once by a
    :func:`parallel` operation (core 0 on the calling thread). The lists
    are filled after the job exists (their WAIT and SIGNAL operations
    refer to it): :meth:`set_lists`."""

    def __init__(self, cores: int):
        self.struct = _JobStruct(cores=cores)
        self.address = ctypes.addressof(self.struct)
        self.lists: list[OpList] = []

    def set_lists(self, lists: list[list[Op]]) -> None:
        """The operations of each core (as many lists as cores)."""
        assert len(lists) == self.struct.cores
        self.lists = [OpList(ops) for ops in lists]
        self._addresses = (ctypes.c_void_p * len(lists))(*(ol.address for ol in self.lists))
        self._counts = (ctypes.c_uint32 * len(lists))(*(ol.count for ol in self.lists))
        self._cursors = (Cursor * len(lists))()
        self.struct.lists = ctypes.addressof(self._addresses)
        self.struct.counts = ctypes.addressof(self._counts)
        self.struct.cursors = ctypes.addressof(self._cursors)


class Flags:
    """One uint64 per firing of a parallel job: the epoch of the job's run
    in which it last ran."""

    def __init__(self, count: int):
        self.array = (ctypes.c_uint64 * max(1, count))()

    def __getitem__(self, k: int) -> int:
        return ctypes.addressof(self.array) + k * ctypes.sizeof(ctypes.c_uint64)


# ====================================================================== channels


class _RingStruct(ctypes.Structure):
    _fields_ = [("data", ctypes.c_void_p), ("capacity", ctypes.c_uint32), ("head", ctypes.c_uint32),
                ("count", ctypes.c_uint32), ("size", ctypes.c_uint32)]


class _StageStruct(ctypes.Structure):
    _fields_ = [("data", ctypes.c_void_p), ("tokens", ctypes.c_uint32), ("cursor", ctypes.c_uint32),
                ("size", ctypes.c_uint32)]


class Ring:
    """A channel's queue of tokens (``el_ring_t``) of type ``t``,
    holding ``capacity`` tokens (the analysis's figure, enough for the
    channel's traffic from its initial tokens on)."""

    def __init__(self, t: T.ValueType, capacity: int, initial: list):
        self.ctype = V.ctype(t)
        self.traffic = capacity
        self.struct = _RingStruct(size=ctypes.sizeof(self.ctype))
        self.address = ctypes.addressof(self.struct)
        self._allocate(max(capacity, len(initial), 1), list(initial))

    def _allocate(self, capacity: int, tokens: list) -> None:
        self.data = (self.ctype * capacity)(*tokens)
        self.struct.data = ctypes.addressof(self.data)
        self.struct.capacity, self.struct.head, self.struct.count = capacity, 0, len(tokens)

    def tokens(self) -> list:
        """The queued tokens, oldest first."""
        s = self.struct
        return [self.data[(s.head + k) % s.capacity] for k in range(s.count)]

    def replace(self, values: list) -> None:
        """The queue becomes ``values`` (a live replacement's tokens). They
        may be more than the channel's traffic leaves at this point, and
        stay more: the ring keeps room for them and for that traffic."""
        tokens = list(values)
        self._allocate(max(self.struct.capacity, len(tokens) + self.traffic), tokens)

    def extend(self, values: list) -> None:
        self.replace(self.tokens() + list(values))


class Stage:
    """A task's staging array of one channel (``el_stage_t``): the tokens
    taken at its release, or those it pushes at its deadline (zero at
    first)."""

    def __init__(self, t: T.ValueType, tokens: int):
        self.type = t
        self.data = (V.ctype(t) * max(1, tokens))()
        self.struct = _StageStruct(data=ctypes.addressof(self.data), tokens=tokens, cursor=0,
                                   size=ctypes.sizeof(V.ctype(t)))
        self.address = ctypes.addressof(self.struct)

    def values(self) -> list:
        return self.data[:self.struct.tokens]


# ====================================================================== the runner


class _Table(ctypes.Structure):
    _fields_ = [("ops", ctypes.c_void_p), ("first", ctypes.c_void_p), ("tick", ctypes.c_void_p),
                ("native", ctypes.c_void_p), ("instants", ctypes.c_uint32), ("hyperperiod", ctypes.c_uint64),
                ("tick_us", ctypes.c_uint64)]


class Cursor(ctypes.Structure):
    """``el_cursor_t``: the next instant of the table (``base`` the current
    hyperperiod's first tick, ``index`` the instant in it), the time of the
    instant being run, and a fault."""

    _fields_ = [("base", ctypes.c_uint64), ("now_us", ctypes.c_uint64), ("index", ctypes.c_uint32),
                ("error", ctypes.c_uint32), ("error_at", ctypes.c_void_p)]

    def __init__(self):
        super().__init__()
        self.pointer = ctypes.c_void_p(ctypes.addressof(self))


class Table:
    """The dispatch table in C: instant k runs ``plans[k]`` (its ticks in the
    hyperperiod in ``ticks``); ``native[k]`` says whether it runs without
    Python."""

    def __init__(self, plans: list[list[Op]], ticks: list[int], native: list[bool], hyperperiod: int, tick_us: int):
        first = [0]
        for plan in plans:
            first.append(first[-1] + len(plan))
        self.ops = OpList([op for plan in plans for op in plan])
        self.first = (ctypes.c_uint32 * len(first))(*first)
        self.ticks = (ctypes.c_uint64 * max(1, len(ticks)))(*ticks)
        self.native = (ctypes.c_uint8 * max(1, len(native)))(*native)
        self.struct = _Table(self.ops.address, ctypes.addressof(self.first), ctypes.addressof(self.ticks),
                             ctypes.addressof(self.native), len(plans), hyperperiod, tick_us)
        self.pointer = ctypes.c_void_p(ctypes.addressof(self.struct))

    def span(self, k: int, start: int, count: int) -> Span:
        """Operations ``start`` .. ``start + count`` of instant k's plan."""
        return self.ops.span(self.first[k] + start, count)


class RunnerFault(Exception):
    """The runner stopped at a fault (``kind`` one of RING_FULL, ...) of the
    ring, stage or operation at address ``at``."""

    def __init__(self, kind: int, at: int):
        super().__init__(kind, at)
        self.kind = kind
        self.at = at


class Runner:
    """The loaded runner library (``runner.c``). Its functions take ctypes
    arguments made beforehand (:class:`Span`, ``Cursor.pointer``): a call
    with conversions would cost more than many operations."""

    def __init__(self, library: ctypes.CDLL):
        self.library = library
        self._run_ops = library.el_run_ops
        self._run_ops.restype = ctypes.c_uint32
        self._run_instants = library.el_run_instants
        self._run_instants.restype = ctypes.c_uint64

    def run(self, span: Span, cursor: Cursor) -> None:
        """Run the operations of ``span``; a fault raises :class:`RunnerFault`."""
        if self._run_ops(*span.args, cursor.pointer):
            raise RunnerFault(cursor.error, cursor.error_at)

    def run_instants(self, table: Table, cursor: Cursor, before_us: int, instants: int, ops: int) -> int:
        """Instants of ``table`` from the cursor on, as long as they run
        without Python, are before ``before_us`` and are at most
        ``instants``; the instant that reaches ``ops`` operations is the
        last. Returns how many ran."""
        done = self._run_instants(table.pointer, cursor.pointer, ctypes.c_uint64(before_us),
                                  ctypes.c_uint64(instants), ctypes.c_uint64(ops))
        if cursor.error:
            raise RunnerFault(cursor.error, cursor.error_at)
        return done
