"""The DDS side of a node's exports (docs/distribution.md, "DDS"): each
export's topic, its ROS 2 type name and IDL, its QoS and when it is
published. Semantics live here; a board that hosts DDS peers prints these
tables and decides nothing.

- A **var** is published at each publication of a task of the node that
  writes it (its deadline), with the var's published value.
- A **channel** is published "as its consumer receives it": at each release
  of its consuming task on the node, with the tokens the release takes.

A sample's source timestamp is the logical time of that instant (ns since
the node's logical time 0), so a subscriber sees the model's instants.

A channel between two PC nodes over a DDS link (:class:`DdsChannel`) is
written by the producer's node at each publication and pushed into the
consumer's input end once its stamp + the link's delay is due.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core import types as T
from .deployment import topic_name

# QoS of every export's writer: reliable, keep-last with ROS 2's default
# depth (the `default` profile of rclcpp and rclpy), transient-local (a
# reader that asks for it gets the last samples written before it matched;
# ROS 2's volatile readers match too).
HISTORY_DEPTH = 10

# EasyLab type -> (std_msgs message, IDL type of its `data` field).
_STD_MSGS = {
    "bool": ("Bool", "boolean"),
    "int8": ("Int8", "int8"),
    "uint8": ("UInt8", "uint8"),
    "int16": ("Int16", "short"),
    "uint16": ("UInt16", "unsigned short"),
    "int32": ("Int32", "long"),
    "uint32": ("UInt32", "unsigned long"),
    "float32": ("Float32", "float"),
}
_IDL_TIME = "unsigned long"  # `time`: whole milliseconds, as in traces


@dataclass
class DdsExport:
    """One export as its node publishes it. ``values`` values of
    ``value_type`` per sample (an item's count, or the tokens a channel's
    consumer takes per release) make the type's ``data`` field."""

    name: str
    kind: str  # var | channel
    target: int  # item id or channel id in the node's program
    link: str
    domain: int
    topic: str  # rt/<model>/<node>/<name>
    module: tuple[str, ...]  # IDL modules of the type: ("std_msgs", "msg", "dds_")
    struct: str  # IDL struct name, with ROS 2's trailing underscore: "Int16_"
    member: str  # IDL type of the `data` field: "short"
    value_type: T.ValueType
    values: int
    trigger_tasks: list[int]  # the node's tasks whose publication (var) or release (channel) publishes it

    @property
    def type_name(self) -> str:
        """The DDS type name, as ROS 2 spells it: ``std_msgs::msg::dds_::Int16_``."""
        return "::".join((*self.module, self.struct))

    @property
    def ros_type(self) -> str:
        """The ROS 2 interface name (``std_msgs/msg/Int16``), for ``ros2 topic echo``."""
        return f"{self.module[0]}/{self.module[1]}/{self.struct[:-1]}"

    @property
    def c_type(self) -> str:
        """The C name idlc gives the type: ``std_msgs_msg_dds__Int16_``."""
        return "_".join((*self.module, self.struct))


def ros_type_of(model: str, name: str, value_type: T.ValueType, values: int) -> tuple[tuple[str, ...], str, str]:
    """(IDL modules, struct name, IDL type of ``data``) of an export: a
    std_msgs message for one value of a type it has, else a struct of the
    model's own (``<model>::msg::dds_::<Name>_`` with ``data`` an array
    when there are several values)."""
    if values == 1 and value_type.name in _STD_MSGS:
        message, member = _STD_MSGS[value_type.name]
        return ("std_msgs", "msg", "dds_"), f"{message}_", member
    member = _IDL_TIME if value_type.name == "time" else _STD_MSGS[value_type.name][1]
    camel = "".join(part[:1].upper() + part[1:] for part in name.split("_"))
    return (model, "msg", "dds_"), f"{camel}_", member


@dataclass
class DdsChannel:
    """A node's end of a channel over a DDS link: ``out`` on the producer's
    node writes each publication's tokens (one sample of ``values`` tokens,
    stamped with its logical time d); ``in`` on the consumer's node pushes a
    sample into the channel's input end at the first instant at or after
    d + ``delay_us`` (the link's latency + jitter, the checker's arrival).
    The producer publishes at ``first_us + k * period_us``: in lock-step the
    consumer waits for every publication due by an instant."""

    name: str
    channel: int  # channel id in the node's program
    direction: str  # out | in
    link: str
    domain: int
    topic: str  # rt/<model>/<producer node>/<channel>
    module: tuple[str, ...]
    struct: str
    member: str
    value_type: T.ValueType
    values: int  # tokens per publication of the producer
    delay_us: int
    first_us: int
    period_us: int

    type_name = DdsExport.type_name
    c_type = DdsExport.c_type


def node_dds_channels(program, node: str, channels) -> list[DdsChannel]:
    """The node's ends of the channels that cross a DDS link, with the node
    program's channel ids (``channels``: old id -> new id)."""
    dep = program.deployment
    links = {lk.name: lk for lk in dep.links}
    found = []
    for crossing in dep.crossings:
        link = links[crossing.link]
        if link.engine != "dds" or node not in (crossing.producer_node, crossing.consumer_node):
            continue
        ch = program.channels[crossing.channel]
        producer = program.tasks[ch.producer_task]
        module, struct, member = ros_type_of(program.name, ch.name, ch.type, ch.tokens_in)
        found.append(DdsChannel(
            ch.name, channels(ch.id), "out" if crossing.producer_node == node else "in", link.name,
            link.settings["domain"], topic_name(program.name, crossing.producer_node, ch.name), module, struct,
            member, ch.type, ch.tokens_in, crossing.delay_us,
            (producer.offset + producer.deadline) * program.tick_us, producer.period * program.tick_us))
    return found


def node_exports(program, node: str, items, channels, tasks) -> list[DdsExport]:
    """The exports published from ``node`` of a distributed ``program``, with
    the node program's ids (``items``, ``channels``, ``tasks``: old id -> new
    id, as the split numbers them)."""
    dep = program.deployment
    links = {lk.name: lk for lk in dep.links}
    found = []
    for spec in dep.exports:
        if spec.node != node:
            continue
        if spec.kind == "var":
            item = program.items[spec.target]
            value_type, values, target = item.type, item.count, items(item.id)
            triggers = [t.id for t in program.tasks if t.id in tasks and item.id in t.writes]
        else:
            ch = program.channels[spec.target]
            value_type, values, target = ch.type, ch.tokens_out, channels(ch.id)
            triggers = [ch.consumer_task]
        module, struct, member = ros_type_of(program.name, spec.name, value_type, values)
        found.append(DdsExport(spec.name, spec.kind, target, spec.link, links[spec.link].settings["domain"],
                               spec.topic, module, struct, member, value_type, values,
                               [tasks(t) for t in triggers]))
    return found


def idl_text(exports: list) -> str:
    """The IDL of every type the exports (and DDS channel ends) use, each once (for idlc)."""
    seen: dict[str, str] = {}
    for e in exports:
        if e.type_name in seen:
            continue
        field = f"{e.member} data[{e.values}];" if e.values > 1 else f"{e.member} data;"
        opening = " ".join(f"module {m} {{" for m in e.module)
        closing = " ".join("};" for _ in e.module)
        seen[e.type_name] = f"{opening}\n  @final struct {e.struct} {{ {field} }};\n{closing}\n"
    return "// DDS types of the exports (generated from the IR; docs/distribution.md)\n" + "".join(seen.values())


__all__ = ["DdsChannel", "DdsExport", "HISTORY_DEPTH", "idl_text", "node_dds_channels", "node_exports",
           "ros_type_of"]
