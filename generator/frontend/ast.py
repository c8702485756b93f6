"""The abstract syntax tree of a model file: frozen dataclasses with spans.

The tree says what was written, nothing more: names are unresolved strings
and expressions are unevaluated. The checker (:mod:`easylab.checker`) turns
it into the resolved model.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from ..core.source import Span

# ---------------------------------------------------------------- expressions


@dataclass(frozen=True)
class Expr:
    span: Span


@dataclass(frozen=True)
class IntLit(Expr):
    value: int


@dataclass(frozen=True)
class RealLit(Expr):
    value: Fraction
    text: str


@dataclass(frozen=True)
class DurationLit(Expr):
    """A duration, exact in microseconds."""

    microseconds: Fraction
    text: str


@dataclass(frozen=True)
class BoolLit(Expr):
    value: bool


@dataclass(frozen=True)
class StringLit(Expr):
    value: str


@dataclass(frozen=True)
class Path(Expr):
    """A (dotted) name: ``x``, ``robot.drive.m1.speed``, ``Extending.time``."""

    parts: tuple[str, ...]
    part_spans: tuple[Span, ...]

    @property
    def text(self) -> str:
        return ".".join(self.parts)


@dataclass(frozen=True)
class Unary(Expr):
    op: str  # "-" or "not"
    operand: Expr


@dataclass(frozen=True)
class Binary(Expr):
    op: str  # "or" "and" "==" "!=" "<" "<=" ">" ">=" "+" "-" "*" "/" "%"
    left: Expr
    right: Expr


# ---------------------------------------------------------------- declarations


@dataclass(frozen=True)
class Node:
    span: Span


@dataclass(frozen=True)
class Named(Node):
    name: str
    name_span: Span


@dataclass(frozen=True)
class TypeRef(Node):
    name: str
    size: Expr | None = None


@dataclass(frozen=True)
class RangeAttr(Node):
    low: Expr
    high: Expr


@dataclass(frozen=True)
class ServiceAttr(Node):
    access: str  # "ro" | "rw"
    address: int | None = None


@dataclass(frozen=True)
class ModelDecl(Named):
    title: str | None


@dataclass(frozen=True)
class Import(Node):
    target: str
    is_library: bool  # `import std` (a library name) vs `import "file.elab"`


@dataclass(frozen=True)
class Const(Named):
    type: TypeRef
    value: Expr


@dataclass(frozen=True)
class Data(Named):
    """A ``param`` or ``var`` declaration."""

    kind: str  # "param" | "var"
    type: TypeRef
    default: Expr | None
    range: RangeAttr | None
    unit: str | None
    service: ServiceAttr | None
    persist: bool
    attr_spans: tuple[tuple[str, Span], ...] = ()
    scale: Fraction | None = None  # engineering value = stored value x scale (``scale 0.1``)


@dataclass(frozen=True)
class Delay(Node):
    """Initial tokens of an edge or channel: a count of zeros, or a list."""

    count: Expr | None
    values: tuple[Expr, ...] | None


@dataclass(frozen=True)
class Placement(Named):
    """``on NODE`` (a task's or device's node) or ``over LINK`` (a channel's
    link): the name it gives."""


@dataclass(frozen=True)
class Channel(Named):
    type: TypeRef
    delay: Delay | None
    over: Placement | None = None


@dataclass(frozen=True)
class FormalParam(Named):
    type: TypeRef
    default: Expr | None
    choices: tuple[Expr, ...] | None = None


@dataclass(frozen=True)
class Actual(Named):
    value: Expr


@dataclass(frozen=True)
class Resource(Node):
    kind: str
    index: Expr | None
    # A device's place on a shared bus: "addr" (an address) or "cs" (a
    # chip-select pin), and its value; None for a resource owned whole.
    select_kind: str | None = None
    select: Expr | None = None


@dataclass(frozen=True)
class DataPort(Named):
    direction: str  # "in" | "out"
    type: TypeRef
    rate: Expr | None


@dataclass(frozen=True)
class DataExport(Named):
    direction: str
    target: Path


@dataclass(frozen=True)
class Part(Named):
    type_name: str
    type_span: Span
    args: tuple[Actual, ...]


@dataclass(frozen=True)
class DriverImpl(Node):
    """``impl BOARD "file.c"`` after a driver: the device's handlers on that
    board, from a C file beside the declaring model file."""

    board: str
    board_span: Span
    file: str


@dataclass(frozen=True)
class ChipModel(Node):
    """``sim "file.c"`` after a driver: the model of the device's chip that
    the simulator harnesses run (sim/el_chip.h), beside the declaring file."""

    file: str


@dataclass(frozen=True)
class DeviceType(Named):
    params: tuple[FormalParam, ...]
    claims: tuple[Resource, ...]
    ports: tuple[DataPort, ...]
    exports: tuple[DataExport, ...]
    parts: tuple[Part, ...]
    driver: str | None
    driver_span: Span | None
    impls: tuple[DriverImpl, ...] = ()
    states: tuple["StateVar", ...] = ()
    chips: tuple[ChipModel, ...] = ()  # at most one (the checker says so)


@dataclass(frozen=True)
class SafeValue(Node):
    """``safe level = true`` after a device's arguments: the value of one
    of its `in` data when nothing drives it."""

    datum: Path  # relative to the device
    value: Expr


@dataclass(frozen=True)
class DeviceInstance(Named):
    type_name: str
    type_span: Span
    args: tuple[Actual, ...]
    node: Placement | None = None
    safe: tuple[SafeValue, ...] = ()


@dataclass(frozen=True)
class TypeParam(Named):
    bound: str | None


@dataclass(frozen=True)
class ActorPort(Named):
    direction: str
    type: TypeRef
    rate: Expr | None


@dataclass(frozen=True)
class StateVar(Named):
    type: TypeRef


@dataclass(frozen=True)
class CodeBlock(Node):
    kind: str  # "start" | "step" | "stop"
    code: str
    code_span: Span


@dataclass(frozen=True)
class ActorType(Named):
    type_params: tuple[TypeParam, ...]
    params: tuple[FormalParam, ...]
    ports: tuple[ActorPort, ...]
    states: tuple[StateVar, ...]
    code: tuple[CodeBlock, ...]
    impl: str | None
    impl_span: Span | None
    cost: object = None  # `cost 20 us`: the time of one firing, for the multi-core plan (docs/multicore.md)
    cost_span: Span | None = None


@dataclass(frozen=True)
class Instance(Named):
    type_name: str
    type_span: Span
    type_args: tuple[TypeRef, ...]
    args: tuple[Actual, ...]


@dataclass(frozen=True)
class Edge(Node):
    src: Path
    dst: Path
    delay: Delay | None


@dataclass(frozen=True)
class Dataflow(Named):
    schedule: str | None  # "sas" | "flat" | "min-buffer" | None
    instances: tuple[Instance, ...]
    edges: tuple[Edge, ...]


@dataclass(frozen=True)
class Assign(Node):
    kind: str  # "entry" | "exit"
    target: Path
    value: Expr


@dataclass(frozen=True)
class Run(Named):
    pass


@dataclass(frozen=True)
class Step(Named):
    initial: bool
    entry: tuple[Assign, ...]
    exit: tuple[Assign, ...]
    runs: tuple[Run, ...]


@dataclass(frozen=True)
class StepRef(Named):
    pass


@dataclass(frozen=True)
class Transition(Node):
    sources: tuple[StepRef, ...]
    targets: tuple[StepRef, ...]
    guard: Expr


@dataclass(frozen=True)
class Chart(Named):
    steps: tuple[Step, ...]
    transitions: tuple[Transition, ...]


@dataclass(frozen=True)
class TaskAttr(Node):
    key: str  # "period" | "offset" | "deadline" | "wcet"
    value: Expr


@dataclass(frozen=True)
class Task(Named):
    attrs: tuple[TaskAttr, ...]
    runs: tuple[Run, ...]
    node: Placement | None = None


@dataclass(frozen=True)
class InterfaceAttr(Node):
    key: str
    value: int | str
    value_span: Span


@dataclass(frozen=True)
class Interface(Node):
    kind: str  # "debug" | "modbus"
    mode: str | None  # modbus: "rtu" | "tcp"
    resource: Resource | None
    attrs: tuple[InterfaceAttr, ...]


# ---------------------------------------------------------------- distribution


@dataclass(frozen=True)
class NodeDecl(Named):
    """``node NAME board B [mcu M] [cores N] ["title"]``."""

    board: str
    board_span: Span
    mcu: str | None
    title: str | None
    cores: int | None = None  # a PC node's cores (docs/multicore.md)
    cores_span: Span | None = None


@dataclass(frozen=True)
class LinkAttr(Node):
    key: str
    value: Expr


@dataclass(frozen=True)
class RemoteAttr(Node):
    key: str  # "watchdog" | "overruns"
    value: Expr


@dataclass(frozen=True)
class LinkMember(Node):
    """A node on a link: ``master N on uart0``, ``slave N on uart0 unit 2``,
    ``peer N``."""

    role: str  # "master" | "slave" | "peer"
    node: str
    node_span: Span
    resource: Resource | None
    attrs: tuple[LinkAttr, ...]


@dataclass(frozen=True)
class LinkDecl(Named):
    engine: str  # "modbus-rtu" | "dds"
    attrs: tuple[LinkAttr, ...]
    members: tuple[LinkMember, ...]


@dataclass(frozen=True)
class Export(Node):
    """``export NAME over LINK``: a var or channel published on a DDS link."""

    name: str
    name_span: Span
    link: Placement


@dataclass(frozen=True)
class RemoteSettings(Node):
    """``remote watchdog 250 ms overruns 5``: remote execution's fault
    reactions (docs/remote.md)."""

    attrs: tuple[RemoteAttr, ...]


Declaration = (Const | Data | Channel | DeviceType | DeviceInstance | ActorType
               | Dataflow | Chart | Task | NodeDecl | LinkDecl)


@dataclass(frozen=True)
class Module:
    """One parsed file."""

    file: str
    header: ModelDecl | None
    imports: tuple[Import, ...]
    declarations: tuple[Named, ...]
    interfaces: tuple[Interface, ...]
    exports: tuple[Export, ...] = ()
    remote: tuple[RemoteSettings, ...] = ()
