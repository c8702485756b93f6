"""The checked model: every name resolved, every constant evaluated.

The checker builds it from the AST; the analyses (SDF, charts, tasks) and
the lowering to the IR read it. Nodes keep a reference to their AST
declaration for source positions only.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

from . import ast
from ..core.types import ValueType


@dataclass
class ConstInfo:
    decl: ast.Const
    type: ValueType
    value: object


@dataclass
class DataInfo:
    """A ``param`` or ``var``."""

    decl: ast.Data
    type: ValueType
    initial: object  # int, bool, Fraction (float32) or Fraction microseconds (time)
    range: tuple[object, object] | None
    writers: list["Writer"] = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.decl.name

    @property
    def kind(self) -> str:
        return self.decl.kind


@dataclass
class Writer:
    """Who writes a var or device input: a dataflow edge or a chart action."""

    owner: object  # DataflowInfo or ChartInfo
    span: object


@dataclass
class ChannelInfo:
    decl: ast.Channel
    type: ValueType
    initial_tokens: tuple
    producers: list["EdgeInfo"] = field(default_factory=list)
    consumers: list["EdgeInfo"] = field(default_factory=list)
    # "produced"/"consumed": the roles some edge names it in, kept or not: a
    # channel whose only producing edge was rejected (a type mismatch) has
    # that error, not also "no producer"
    named_as: set = field(default_factory=set)
    link: "LinkInfo | None" = None  # the link it crosses between nodes (`over`)

    @property
    def name(self) -> str:
        return self.decl.name


@dataclass
class DevicePort:
    name: str
    direction: str
    type: ValueType
    rate: int
    array: bool = False  # declared with a rate: an array in handler code, even for rate 1


@dataclass
class Claim:
    kind: str
    index: object  # int or str
    span: object
    owner: str  # a device path or an interface name
    # A device's place on a shared bus: ("addr", 0x48) or ("cs", "PB2");
    # None when the claim owns the resource whole.
    select: tuple[str, object] | None = None
    node: str | None = None  # the node whose resource it is, in a model of nodes

    @property
    def key(self) -> tuple:
        return (self.node, self.kind, self.index, self.select)

    @property
    def resource(self) -> tuple:
        """The resource itself, whatever the place on it."""
        return (self.node, self.kind, self.index)

    def __str__(self) -> str:
        text = f"{self.kind}[{_claim_value(self.index)}]"
        if self.select is not None:
            how, value = self.select
            text += f" {how} {f'0x{value:02x}' if how == 'addr' else _claim_value(value)}"
        return text


def _claim_value(value) -> str:
    return f'"{value}"' if isinstance(value, str) else str(value)


@dataclass
class PrimitiveDevice:
    """A device with a driver, at a path such as ``robot.drive.m1``."""

    path: str
    type: ast.DeviceType
    driver: str
    args: dict[str, object]
    ports: dict[str, DevicePort]
    claims: list[Claim]
    span: object  # where the instance or part is declared
    handlers: dict[str, str] = field(default_factory=dict)  # board -> its handler file (absolute)
    states: list[tuple[str, ValueType, int | None]] = field(default_factory=list)  # (name, type, array size)
    chip: str | None = None  # its chip model for the simulator harnesses (absolute), `sim "FILE.c"`


@dataclass
class DeviceDatum:
    """One port of a primitive device, as the application sees it."""

    device: PrimitiveDevice
    port: DevicePort
    name: str  # the path the model uses for it first, e.g. "sensor.raw"
    writers: list[Writer] = field(default_factory=list)
    safe: object = None  # `in` data: the declared safe value (a checked constant), None = zero/false

    @property
    def type(self) -> ValueType:
        return self.port.type


@dataclass
class ActorInstanceInfo:
    decl: ast.Instance
    actor_type: ast.ActorType
    type_bindings: dict[str, ValueType]
    args: dict[str, "ArgValue"]
    port_types: dict[str, ValueType]
    port_rates: dict[str, int]
    state_types: dict[str, tuple[ValueType, int | None]]  # (type, array size)
    dataflow: "DataflowInfo | None" = None

    @property
    def name(self) -> str:
        return self.decl.name


@dataclass
class ArgValue:
    """An actor argument: a constant, or an expression over params (latched)."""

    type: ValueType
    const: object | None
    expr: ast.Expr | None
    params: tuple[str, ...] = ()
    node: object = None  # the typed IR expression (easylab.irexpr) when not constant


@dataclass
class Endpoint:
    """One end of a dataflow edge."""

    kind: str  # actor | var | param | device | channel
    target: object  # ActorInstanceInfo, DataInfo, DeviceDatum or ChannelInfo
    port: str | None  # actor port name
    type: ValueType
    rate: int | None  # None for a channel: set by the graph
    path: ast.Path

    @property
    def label(self) -> str:
        return self.path.text


@dataclass
class EdgeInfo:
    decl: ast.Edge
    src: Endpoint
    dst: Endpoint
    initial_tokens: tuple

    @property
    def label(self) -> str:
        return f"{self.src.label} -> {self.dst.label}"


@dataclass
class DataflowInfo:
    decl: ast.Dataflow
    instances: dict[str, ActorInstanceInfo]
    edges: list[EdgeInfo]
    task: "TaskInfo | None" = None
    analysis: object = None  # the SDF analysis, filled in by easylab.analysis

    @property
    def name(self) -> str:
        return self.decl.name


@dataclass
class StepInfo:
    decl: ast.Step
    index: int
    branch: tuple  # the parallel branch: ((transition index, branch index), ...)
    runs: list[DataflowInfo]
    entry_actions: list["ActionInfo"] = field(default_factory=list)
    exit_actions: list["ActionInfo"] = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.decl.name


@dataclass
class ActionInfo:
    """``target = value`` of an entry or exit action; ``target`` is a DataInfo
    or DeviceDatum, ``value`` a typed IR expression of the target's type."""

    decl: ast.Assign
    target: object
    value: object


@dataclass
class TransitionInfo:
    decl: ast.Transition
    index: int
    sources: list[StepInfo]
    targets: list[StepInfo]
    guard: object = None  # typed IR expression (bool)


@dataclass
class ChartInfo:
    decl: ast.Chart
    steps: dict[str, StepInfo]
    transitions: list[TransitionInfo]
    initial: StepInfo | None
    task: "TaskInfo | None" = None

    @property
    def name(self) -> str:
        return self.decl.name


@dataclass
class TaskInfo:
    decl: ast.Task
    period_us: Fraction
    offset_us: Fraction
    deadline_us: Fraction
    wcet_us: Fraction | None
    runs: list  # DataflowInfo | ChartInfo, in order

    @property
    def name(self) -> str:
        return self.decl.name


@dataclass
class InterfaceInfo:
    decl: ast.Interface
    kind: str  # debug | modbus-rtu | modbus-tcp
    claim: Claim | None
    settings: dict[str, object]


@dataclass
class NodeInfo:
    """A node: one program on one board (docs/distribution.md)."""

    decl: ast.NodeDecl
    board: str
    mcu: str | None

    @property
    def name(self) -> str:
        return self.decl.name


@dataclass
class LinkMemberInfo:
    node: NodeInfo
    role: str  # master | slave | peer
    uart: Claim | None  # the UART it is on (a claim of its node)
    unit: int | None  # a slave's Modbus unit id
    decl: ast.LinkMember


@dataclass
class LinkInfo:
    """A link over an existing engine. ``settings`` are constants in their
    run-time units: baud, parity, and durations in microseconds (round,
    turnaround, jitter, latency) or the DDS domain."""

    decl: ast.LinkDecl
    engine: str  # modbus-rtu | dds
    settings: dict[str, object]
    members: list[LinkMemberInfo]

    @property
    def name(self) -> str:
        return self.decl.name

    def member(self, node: str) -> LinkMemberInfo | None:
        return next((m for m in self.members if m.node.name == node), None)


@dataclass
class ExportInfo:
    """A var or channel published on a DDS link from ``node``."""

    decl: ast.Export
    target: object  # DataInfo or ChannelInfo
    link: LinkInfo
    node: NodeInfo


@dataclass
class RemoteInfo:
    """``remote watchdog T overruns K``: None where the model keeps the
    default (docs/remote.md)."""

    decl: ast.RemoteSettings
    watchdog_us: int | None
    overrun_limit: int | None


@dataclass
class CheckedModel:
    """A model that passed the checker."""

    name: str
    title: str | None
    file: str
    consts: dict[str, ConstInfo]
    data: dict[str, DataInfo]
    channels: dict[str, ChannelInfo]
    device_types: dict[str, ast.DeviceType]
    devices: list[PrimitiveDevice]
    device_data: dict[str, DeviceDatum]  # every path that names a datum
    top_devices: dict[str, ast.DeviceInstance]
    actor_types: dict[str, ast.ActorType]
    dataflows: dict[str, DataflowInfo]
    charts: dict[str, ChartInfo]
    tasks: dict[str, TaskInfo]
    interfaces: list[InterfaceInfo]
    claims: list[Claim]
    actor_type_files: dict[str, str] = field(default_factory=dict)
    actor_costs: dict[str, int] = field(default_factory=dict)  # declared `cost` of one firing, ns, by actor type
    # Distribution (empty for a model without nodes): the nodes, the links,
    # where each task and primitive device runs, the exports.
    nodes: dict[str, NodeInfo] = field(default_factory=dict)
    links: dict[str, LinkInfo] = field(default_factory=dict)
    task_nodes: dict[str, str] = field(default_factory=dict)  # task name -> node name
    device_nodes: dict[str, str] = field(default_factory=dict)  # primitive device path -> node name
    exports: list[ExportInfo] = field(default_factory=list)
    remote: RemoteInfo | None = None
