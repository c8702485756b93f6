"""Where a program runs: the nodes of a distributed model, its links, the
channels that cross them and the exports (docs/distribution.md).

A program lowered from a model without nodes has no deployment. Channels
and tasks are named by their ids in the whole program; :mod:`.split` makes
one program per node from it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the round table is the timing analysis's, carried as data
    from ..analysis.distribution import RoundTable


@dataclass
class NodeSpec:
    name: str
    board: str
    mcu: str | None
    title: str | None
    cores: int = 1  # `cores N`: a multi-core build where the plan says it pays (docs/multicore.md)


@dataclass
class LinkMember:
    node: str
    role: str  # master | slave | peer
    uart: str | None  # the UART it is on, as written (uart[0])
    unit: int | None  # a slave's Modbus unit id


@dataclass
class LinkSpec:
    """A link: ``engine`` is modbus-rtu or dds; ``settings`` in run-time
    units (baud, parity; round, turnaround, jitter and latency in µs; the
    DDS domain)."""

    name: str
    engine: str
    settings: dict
    members: list[LinkMember]


@dataclass
class Crossing:
    """A channel whose producing and consuming tasks run on two nodes."""

    channel: int  # channel id in the whole program
    link: str
    producer_node: str
    consumer_node: str
    delay_us: int = 0  # over DDS: a value published at d is usable from d + delay_us (latency + jitter)


@dataclass
class ExportSpec:
    """A var or channel published on a DDS link from ``node``, on ``topic``."""

    name: str
    kind: str  # var | channel
    target: int  # item id or channel id
    link: str
    node: str
    topic: str


@dataclass
class Deployment:
    nodes: list[NodeSpec]
    links: list[LinkSpec]
    task_nodes: dict[int, str]  # task id -> node
    device_nodes: dict[int, str]  # device id -> node
    crossings: list[Crossing]
    exports: list[ExportSpec]
    rounds: dict[str, "RoundTable"] = field(default_factory=dict)  # Modbus link -> its round table

    def node(self, name: str) -> NodeSpec:
        return next(n for n in self.nodes if n.name == name)


def topic_name(model: str, node: str, name: str) -> str:
    """The DDS topic of an export, as ROS 2 names topics: ``rt/<model>/<node>/<name>``."""
    return f"rt/{model}/{node}/{name}"
