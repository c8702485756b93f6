"""The IR: one lowered, board-independent program (docs/ir.md).

The IR is the only contract between the front end and the backends (C code
generation, the interpreter, the debug and service maps): a backend never
looks at the AST or the checked model. Everything is resolved to ids,
types, sizes, schedules and tables here; semantics that a backend must
follow are documented in docs/ir.md, once.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from fractions import Fraction

from ..analysis.sdf.schedule import Fire, Loop, Schedule  # the schedule notation is part of the IR
from ..core import expr as I
from ..core import types as T
from ..core.source import Span

__all__ = ["Fire", "Loop", "Schedule"]  # re-exported: backends take the schedule notation from here

IR_VERSION = 1
# How late an instant may be and still be seen as due with 16-bit ticks (µs):
# far beyond what a firmware survives (the MCU boards' watchdogs reset it
# after about 2 s), and beyond any halt (the debugger resynchronises).
TICK_16_HEADROOM_US = 10_000_000


def location(span: Span | None) -> str:
    return f"{span.file}:{span.line}" if span else "?"


# ====================================================================== items


@dataclass
class Item:
    """A published value: a param, a var or a device datum.

    ``initial`` is in run-time units (time: ms; float32: float). Device data
    have ``count`` values (the port's rate)."""

    id: int
    name: str
    kind: str  # param | var | dev_out | dev_in
    type: T.ValueType
    count: int
    initial: object
    location: str
    range: tuple | None = None
    unit: str | None = None
    service: str | None = None  # "ro" | "rw"
    address: int | None = None
    persist: bool = False
    device: int | None = None
    port: str | None = None
    writer_task: int | None = None  # the one task that writes it, if any
    scale: str | None = None  # decimal text: engineering value = value x scale (None: 1)


@dataclass
class Status(Item):
    """A read-only fault counter of a link (docs/ir.md, "Status items"):
    made by the IR from the model's structure (``ir/status.py``), never by
    a backend. ``kind`` is ``status``; ``fault`` says what it counts
    (``overruns``, ``tardy``, ``unanswered``) and ``subject`` of what (a
    task id, a channel id, a slave's slot in its link's round). A uint16
    that saturates at 65535; ``id`` is its index in ``Program.status``."""

    fault: str = ""
    subject: int = 0


@dataclass
class Device:
    """A primitive device. ``claims`` are written as in the model
    (``pin["PB5"]``, ``i2c[0] addr 0x48``). ``handlers`` name, per board,
    the C file from the model's folder that implements the device's
    handlers there (docs/language.md, "Device handlers"); on a board with
    none the board's own driver ``driver`` runs. ``params`` are the
    arguments with their types (run-time units, as items' initial values)
    and ``states`` what the model's handlers keep per device."""

    id: int
    path: str
    driver: str
    type_name: str
    args: dict
    items: list[int]  # its data, in port order
    claims: list[str]
    location: str
    read_by: list[int] = field(default_factory=list)  # tasks reading its out data
    written_by: int | None = None  # the task driving its in data
    handlers: dict[str, str] = field(default_factory=dict)  # board -> handler file (absolute)
    params: dict[str, tuple[T.ValueType, object]] = field(default_factory=dict)
    states: list[tuple[str, T.ValueType, int | None]] = field(default_factory=list)
    array_ports: list[str] = field(default_factory=list)  # data declared with a rate (arrays in C)
    chip: str | None = None  # the model of its chip the simulator harnesses run (absolute; sim/el_chip.h)


# ====================================================================== actors


@dataclass
class Port:
    """An actor port; ``array`` when declared with ``rate`` (an array in C
    even when the rate is 1)."""

    name: str
    direction: str
    type: T.ValueType
    rate: int
    array: bool


@dataclass
class ActorSpec:
    """One specialisation of an actor type: type bindings and constant
    arguments fixed. Instances with equal specs share their code."""

    id: int
    type_name: str
    c_name: str
    type_bindings: dict[str, T.ValueType]
    const_args: dict[str, tuple[T.ValueType, object]]
    runtime_params: dict[str, T.ValueType]  # parameters computed at each firing
    ports: list[Port]
    states: list[tuple[str, T.ValueType, int | None]]
    code: dict[str, str]  # start / step / stop inline C
    impl: str | None  # path of the impl file
    location: str
    cost_ns: int | None = None  # declared `cost` of one firing (docs/multicore.md); not part of the program's id


@dataclass
class ActorInstance:
    id: int
    dataflow: int
    name: str  # instance name inside its dataflow
    spec: int
    runtime_args: dict[str, I.IExpr]
    location: str


@dataclass
class Buffer:
    """An edge between two schedule nodes (actors or external endpoints).

    ``src``/``dst`` are node names of the dataflow's schedule; ``src_port``
    and ``dst_port`` the actor ports (None at an external endpoint)."""

    id: int
    src: str
    src_port: str | None
    dst: str
    dst_port: str | None
    type: T.ValueType
    prod: int
    cons: int
    size: int  # tokens, from the verified schedule
    initial: list
    location: str


@dataclass
class External:
    """An external endpoint: ``in:`` nodes read, ``out:`` nodes write, once per
    activation (a channel endpoint moves ``tokens`` per activation)."""

    node: str
    direction: str  # "in" | "out"
    kind: str  # item | channel
    target: int  # item id or channel id
    tokens: int


@dataclass
class Dataflow:
    id: int
    name: str
    instances: list[int]
    buffers: list[Buffer]
    externals: list[External]
    schedule: Schedule  # over instance names and external node names
    schedule_kind: str
    repetitions: dict[str, int]
    task: int | None
    location: str


# ====================================================================== charts


@dataclass
class Action:
    target: int  # item id
    value: I.IExpr
    location: str


@dataclass
class Step:
    id: int  # index in its chart
    name: str
    slot: int  # the parallel branch (continuation slot) it runs in
    initial: bool
    entry: list[Action]
    exit: list[Action]
    runs: list[int]  # dataflow ids
    location: str


@dataclass
class Transition:
    id: int
    sources: list[int]  # step ids
    targets: list[int]
    guard: I.IExpr
    location: str


@dataclass
class Chart:
    id: int
    name: str
    steps: list[Step]
    transitions: list[Transition]
    slots: int  # number of continuation slots (parallel branches)
    initial: int
    task: int | None
    period_ms: int | None  # Step.time advances by this per activation
    location: str

    @property
    def fired_type(self) -> T.ValueType:
        """The type of the chart's last fired transition (docs/ir.md,
        "Charts"): a transition's id, or all ones (``fired_none``) before the
        first: uint8 while the ids leave that value free (at most 255
        transitions), else uint16."""
        return T.UINT8 if len(self.transitions) <= 0xFF else T.UINT16

    @property
    def fired_none(self) -> int:
        """The value of the last fired transition before any fired."""
        return self.fired_type.max


# ====================================================================== tasks


@dataclass
class Channel:
    id: int
    name: str
    type: T.ValueType
    capacity: int
    initial: list
    producer_task: int
    consumer_task: int
    tokens_in: int
    tokens_out: int
    location: str


@dataclass
class Task:
    """``runs`` lists ("dataflow", id) and ("chart", id) in order. ``reads``
    are the items latched at release, ``writes`` those published at the
    deadline (a task has one local copy of every item it reads or writes)."""

    id: int
    name: str
    period: int  # ticks
    offset: int
    deadline: int
    wcet_us: int | None
    runs: list[tuple[str, int]]
    reads: list[int]
    writes: list[int]
    channels_in: list[int]
    channels_out: list[int]
    location: str


@dataclass
class Instant:
    tick: int
    publish: list[int]
    release: list[int]


@dataclass
class Interface:
    kind: str  # debug | modbus-rtu | modbus-tcp
    resource: str | None
    settings: dict


@dataclass
class RemoteSettings:
    """Remote execution's fault reactions as the model sets them
    (``remote watchdog T overruns K``; docs/remote.md): None keeps the
    device model's default."""

    watchdog_us: int | None = None
    overrun_limit: int | None = None
    location: str = "?"
    watchdog_location: str = "?"  # FILE:LINE:COL of the watchdog time


@dataclass
class Program:
    name: str
    title: str | None
    source: str
    program_id: int
    tick_us: int
    hyperperiod: int
    items: list[Item]
    devices: list[Device]
    specs: list[ActorSpec]
    instances: list[ActorInstance]
    dataflows: list[Dataflow]
    charts: list[Chart]
    channels: list[Channel]
    tasks: list[Task]
    instants: list[Instant]
    interfaces: list[Interface]
    # Where it runs, for a model of several nodes (ir/deployment.py); None for one board.
    deployment: object = None
    remote: RemoteSettings | None = None  # None: the defaults
    # Fault counters of the links the program runs over (ir/status.py); empty for one board.
    status: list[Status] = field(default_factory=list)
    # A node's DDS exports (ir/dds.py: DdsExport), from the split; empty elsewhere.
    exports: list = field(default_factory=list)
    # A node's ends of channels over DDS links (ir/dds.py: DdsChannel), from the split; empty elsewhere.
    dds_channels: list = field(default_factory=list)

    def item(self, name: str) -> Item:
        return next(i for i in self.items if i.name == name)

    # The dispatcher's widths (docs/ir.md, "Dispatcher widths"): derived
    # from the timing, so not part of the dump (the program id).

    @property
    def task_mask_bits(self) -> int:
        """Bits of the dispatcher's task masks: 8, 16 or 32, a bit per task."""
        return next(bits for bits in (8, 16, 32) if len(self.tasks) <= bits)

    @property
    def tick_bits(self) -> int:
        """16 when the dispatcher's ticks may wrap at 2^16, else 32: every
        span it compares wrap-safely (a tick of the dispatch table, a gap
        between instants, a deadline, all within the hyperperiod) is under
        2^15 ticks, and 2^15 ticks last at least TICK_16_HEADROOM_US, so an
        instant that late is still seen as due and counted late."""
        longest = max([self.hyperperiod, *(t.deadline for t in self.tasks)])
        fits = longest < 1 << 15 and (1 << 15) * self.tick_us >= TICK_16_HEADROOM_US
        return 16 if fits else 32


# ====================================================================== identity


def _left_out(value, field: str) -> bool:
    """Fields the IR's JSON (and so the program id) leaves out: an item's
    scale when it has none (the JSON of models before scales), an actor's
    cost (a planning hint: the same code with or without)."""
    return (field == "scale" and getattr(value, field) is None) or \
        (field == "cost_ns" and isinstance(value, ActorSpec))


def to_json(program: Program) -> dict:
    """A canonical, JSON-serialisable dump of the IR (also hashed for the id)."""
    def conv(value):
        if isinstance(value, Program):  # a one-board program, a node without DDS or status items: as before them
            return {k: conv(getattr(value, k)) for k in value.__dataclass_fields__
                    if not (k in ("deployment", "status", "exports", "dds_channels") and not getattr(value, k))}
        if isinstance(value, T.ValueType):
            return value.name
        if isinstance(value, (Schedule,)):
            return value.text()
        if isinstance(value, I.IExpr):
            return _expr_json(value)
        if isinstance(value, Fraction):
            return str(value)
        if hasattr(value, "__dataclass_fields__"):
            return {k: conv(getattr(value, k)) for k in value.__dataclass_fields__ if not _left_out(value, k)}
        if isinstance(value, dict):
            return {str(k): conv(v) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [conv(v) for v in value]
        return value
    return conv(program)


def _expr_json(e: I.IExpr):
    if isinstance(e, I.Const):
        return ["const", e.type.name, e.value if not isinstance(e.value, Fraction) else str(e.value)]
    if isinstance(e, I.Ref):
        return ["ref", e.kind, e.name]
    if isinstance(e, I.Unary):
        return [e.op, _expr_json(e.arg)]
    if isinstance(e, I.Convert):
        return ["convert", e.type.name, _expr_json(e.arg)]
    return [e.op, e.operand_type.name, _expr_json(e.left), _expr_json(e.right)]


def program_id(program: Program) -> int:
    """A 32-bit hash of the IR: matches a firmware to its debug map."""
    dump = to_json(program)
    dump["program_id"] = 0
    dump["source"] = ""
    digest = hashlib.sha256(json.dumps(dump, sort_keys=True).encode()).digest()
    return int.from_bytes(digest[:4], "big")
