"""A DDS subscriber that knows nothing of EasyLab: it sees a topic as a
ROS 2 tool does, by its DDS name and ROS 2 type name alone, with the PyPI
`cyclonedds` binding (its own libddsc).

    python ros2_listener.py --domain 42 --topic rt/m/pc/level \
        --type std_msgs::msg::dds_::Int16_ --field int16 [--length N] --seconds 10

Prints "ready" once its reader exists, then one JSON line per sample:
{"t": source timestamp in ns, "data": value (a list for an array)}. It
ends after --seconds, or --idle seconds without a sample once one came.
QoS as ROS 2's default profile: reliable, keep-last 10, volatile (with
--transient-local: the samples a writer keeps for late joiners too).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import types
from dataclasses import dataclass

import cyclonedds.idl.types as idl_types
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

FIELD_TYPES = {"bool": bool, "int8": idl_types.int8, "uint8": idl_types.uint8, "int16": idl_types.int16,
               "uint16": idl_types.uint16, "int32": idl_types.int32, "uint32": idl_types.uint32,
               "float32": idl_types.float32}


def _struct(type_name: str, member):
    """A struct named ``type_name`` (the DDS type name) with one field ``data``."""
    cls = types.new_class(type_name.split("::")[-1], (IdlStruct,), {"typename": type_name},
                          lambda ns: ns.update({"__annotations__": {"data": member}}))
    return dataclass(cls)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--domain", type=int, required=True)
    parser.add_argument("--topic", required=True)
    parser.add_argument("--type", required=True, dest="type_name")
    parser.add_argument("--field", required=True, choices=sorted(FIELD_TYPES))
    parser.add_argument("--length", type=int, default=1)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--idle", type=float, default=1.0)
    parser.add_argument("--transient-local", action="store_true",
                        help="ask for the writer's last samples on matching (a late joiner's history)")
    args = parser.parse_args()

    participant = DomainParticipant(args.domain)
    topic = Topic(participant, args.topic, _struct(args.type_name, _member(args.field, args.length)))
    qos = Qos(Policy.Reliability.Reliable(max_blocking_time=100_000_000), Policy.History.KeepLast(10),
              *([Policy.Durability.TransientLocal] if args.transient_local else []))
    reader = DataReader(participant, topic, qos=qos)
    print("ready", flush=True)
    end = time.monotonic() + args.seconds
    last = None
    while time.monotonic() < end and (last is None or time.monotonic() - last < args.idle):
        for sample in reader.take(N=256):
            if not sample.sample_info.valid_data:  # the writer's end: no value
                continue
            data = sample.data
            print(json.dumps({"t": sample.sample_info.source_timestamp,
                              "data": list(data) if args.length > 1 else data}), flush=True)
            last = time.monotonic()
        time.sleep(0.002)
    return 0


def _member(field: str, length: int):
    member = FIELD_TYPES[field]
    return idl_types.array[member, length] if length > 1 else member


if __name__ == "__main__":
    sys.exit(main())
