"""The debug interface's outputs (docs/protocol.md): the debug map and the
C tables of the debug server.

Registered in ``render.PRODUCERS`` (files beside model.c) and
``render.INTERFACE_HOOKS`` (starting and polling the server). A model has a
debug interface when it declares one (``debug on uart0``); a release build
never has one. For a debug build this writes:

- ``el_debug_config.h``: ``EL_DEBUG_SERVER`` 1 or 0 (the runtime's
  el_debug.h reads it; with 0 the server and every probe compile to
  nothing);
- with a debug interface, ``debug_tables.c`` (templates/debug_tables.c.j2:
  items with addresses, types, flags and ranges; actor instances; charts'
  continuation slots) and ``debug_map.json`` (what the host tools need to
  name things: program id, items with id, type, flags, unit and location;
  charts, steps, transitions, actors and tasks with their ids).

Debug item ids: the IR's items keep their ids (params, vars, device data);
the state variables of actor instances follow, instance by instance, then
the program's status items (the links' fault counters, read-only), then
the `state` fields of the devices that run the model's handlers on the
board (``DEVICE.FIELD``, read-only: the handlers own them), then the
charts' state, chart by chart: ``Chart.active`` (the step of each parallel
branch), ``Chart.Step.time`` per step and ``Chart.fired`` (the transition
it fired last; read-only: the evolutions own them).
"""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

from ..core import types as T
from ..core.paths import runtime_dir
from ..core.debug_protocol import parse_protocol_header, protocol_constants, protocol_header_path  # noqa: F401 (re-exported)
from . import device_state
from ..ir.program import Program
from .c_syntax import ident

MAP_FORMAT = "easylab-debug-map"
MAP_VERSION = 1

_TYPE_ENUM = {"bool": "EL_DBG_T_BOOL", "int8": "EL_DBG_T_I8", "uint8": "EL_DBG_T_U8", "int16": "EL_DBG_T_I16",
              "uint16": "EL_DBG_T_U16", "int32": "EL_DBG_T_I32", "uint32": "EL_DBG_T_U32",
              "float32": "EL_DBG_T_F32", "time": "EL_DBG_T_TIME"}
_KIND_ENUM = {"param": "EL_DBG_K_PARAM", "var": "EL_DBG_K_VAR", "dev_out": "EL_DBG_K_DEV_OUT",
              "dev_in": "EL_DBG_K_DEV_IN", "state": "EL_DBG_K_STATE", "status": "EL_DBG_K_STATUS",
              "dev_state": "EL_DBG_K_DEV_STATE", "chart": "EL_DBG_K_CHART", "step_time": "EL_DBG_K_STEP_TIME",
              "fired": "EL_DBG_K_FIRED"}
# What the debugger may write (docs/protocol.md "What is writable"): the
# application's inputs and state. A device `in` datum is the application's
# output to an actuator, rewritten at every publication: read-only; so is
# a status item, a fault counter of the links, and a device's state,
# which only its handlers change; so is a chart's state (its active steps,
# its steps' times, the transition it fired last), which only its evolutions
# change.
WRITABLE_KINDS = ("param", "var", "dev_out", "state")
CHART_KINDS = ("chart", "step_time", "fired")


def has_debug_interface(program: Program) -> bool:
    return any(i.kind == "debug" for i in program.interfaces)


@dataclass
class DebugItem:
    """One debug item: a model item or an actor instance's state variable."""

    id: int
    name: str
    kind: str
    type: T.ValueType
    count: int
    c_addr: str  # address expression in debug_tables.c
    c_extern: str | None  # its declaration there (model items), or None
    range: tuple | None
    unit: str | None
    location: str
    actor: int | None = None
    range_index: int | None = None
    chart: int | None = None  # a chart's state: the chart's id
    step: int | None = None  # a step's time: the step's id in its chart
    scale: str | None = None  # a model item's scale (decimal text), None: 1

    @property
    def writable(self) -> bool:
        return self.kind in WRITABLE_KINDS

    @property
    def flags(self) -> list[str]:
        return ["read"] + (["write"] if self.writable else []) + (["range"] if self.range is not None else [])

    @property
    def c_flags(self) -> str:
        names = {"read": "EL_DBG_F_READ", "write": "EL_DBG_F_WRITE", "range": "EL_DBG_F_RANGE"}
        return " | ".join(names[f] for f in self.flags)

    @property
    def c_type(self) -> str:
        return _TYPE_ENUM[self.type.name]

    @property
    def c_kind(self) -> str:
        return _KIND_ENUM[self.kind]


def _bound(t: T.ValueType, value) -> str:
    """A C initialiser of el_dbg_bound_t for a range bound (run-time units).
    C89 initialises a union through its first member only, the int32_t
    `i`: an unsigned bound is its two's complement bits there, a float
    bound its IEEE 754 bits (which `.f` reads back; el_dbg_check_float)."""
    if t is T.FLOAT32:
        bits = struct.unpack("<i", struct.pack("<f", float(value)))[0]
        return f"{{ {_int32(bits)} /* {float(value)!r}f */ }}"
    v = int(value)
    if not t.signed and v > 2**31 - 1:
        return f"{{ {_int32(v - 2**32)} /* {v}UL */ }}"
    return f"{{ {_int32(v)} }}"


def _int32(v: int) -> str:
    return "(-2147483647L - 1L)" if v == -2**31 else f"{v}L"


def debug_items(program: Program, view) -> list[DebugItem]:
    """Every debug item with its debug id (model items, actor states,
    status items, then device states)."""

    items: list[DebugItem] = []
    for iv in view.items:
        it = iv.item
        if it.type.name not in _TYPE_ENUM:
            continue
        decl = f"extern {iv.c_type} {iv.c_name}{f'[{it.count}]' if it.count > 1 else ''};"
        items.append(DebugItem(it.id, it.name, it.kind, it.type, it.count, f"(void *){iv.addr}", decl,
                               it.range, it.unit, it.location, scale=it.scale))
    next_id = len(program.items)
    for inst in program.instances:
        spec = program.specs[inst.spec]
        df = program.dataflows[inst.dataflow]
        c_inst = f"el_a{inst.id}_{ident(inst.name)}"
        for name, t, size in spec.states:
            if t.name not in _TYPE_ENUM:
                continue
            addr = f"(void *){c_inst}.{name}" if size else f"(void *)&{c_inst}.{name}"
            items.append(DebugItem(next_id, f"{df.name}.{inst.name}.{name}", "state", t, size or 1, addr, None,
                                   None, None, inst.location, actor=inst.id))
            next_id += 1
    declared = set()
    for sv in view.status:  # the links' fault counters (docs/ir.md, "Status items")
        st = sv.item
        decl = None if sv.c_extern in declared else sv.c_extern  # one declaration of an array of counters
        declared.add(sv.c_extern)
        items.append(DebugItem(next_id, st.name, "status", st.type, 1, f"(void *){sv.addr}", decl,
                               None, None, st.location))
        next_id += 1
    typed = set()
    for dev, name, t, count, addr in device_state.state_items(program, view.board):
        decl = None
        if dev.id not in typed:  # the state's type and the firmware's (or the library's) variable, once
            typed.add(dev.id)
            var = f"el_mdev{dev.id}_state_t el_mdev{dev.id}_state;"
            # the library holds a copy the interpreter refreshes (generator/interp/interfaces.py)
            decl = "\n".join(device_state.state_type_lines(dev) + [f"extern {var} /* {dev.path} */"]
                             + ([var] if view.library else []))
        items.append(DebugItem(next_id, f"{dev.path}.{name}", "dev_state", t, count, f"(void *){addr}", decl,
                               None, None, dev.location))
        next_id += 1
    for c, p in chart_views(program, view):  # the charts' state: read-only, last (docs/protocol.md, "Items")
        items.append(DebugItem(next_id, f"{c.name}.active", "chart", T.UINT8, c.slots, f"(void *){p}_slot", None,
                               None, None, c.location, chart=c.id))
        next_id += 1
        for st in c.steps:
            items.append(DebugItem(next_id, f"{c.name}.{st.name}.time", "step_time", T.TIME, 1,
                                   f"(void *)&{p}_elapsed[{st.id}u]", None, None, "ms", st.location,
                                   chart=c.id, step=st.id))
            next_id += 1
        items.append(DebugItem(next_id, f"{c.name}.fired", "fired", c.fired_type, 1, f"(void *)&{p}_fired", None,
                               None, None, c.location, chart=c.id))
        next_id += 1
    ranged = 0
    for d in items:
        if d.range is not None:
            d.range_index = ranged
            ranged += 1
    return items


def chart_views(program: Program, view) -> list:
    """(chart, its C prefix) of every chart: the prefix of its ``_slot``
    and ``_elapsed`` arrays in model.c (or the interfaces library)."""
    prefixes = {c["chart"].id: c["p"] for c in view.charts}
    return [(c, prefixes[c.id]) for c in program.charts]


def debug_map(program: Program, items: list[DebugItem]) -> dict:
    """The debug map (debug_map.json): names for the ids the protocol uses."""
    tick = program.tick_us
    return {
        "format": MAP_FORMAT,
        "version": MAP_VERSION,
        "model": program.name,
        "title": program.title,
        "program_id": f"0x{program.program_id:08x}",
        "tick_us": tick,
        "interface": next(({"resource": i.resource, **i.settings} for i in program.interfaces
                           if i.kind == "debug"), None),
        "items": [{
            "id": d.id, "name": d.name, "kind": d.kind, "type": d.type.name, "count": d.count,
            "flags": d.flags, "unit": d.unit,
            "range": list(d.range) if d.range is not None else None,
            "location": d.location,
            **({"actor": d.actor} if d.actor is not None else {}),
            **({"chart": d.chart} if d.chart is not None else {}),
            **({"step": d.step} if d.step is not None else {}),
            **({"scale": T.scale_number(d.scale)} if d.scale is not None else {}),
        } for d in items],
        "charts": [{
            "id": c.id, "name": c.name, "task": c.task, "location": c.location, "slots": c.slots,
            "steps": [{"id": s.id, "name": s.name, "slot": s.slot, "location": s.location} for s in c.steps],
            "transitions": [{
                "id": t.id,
                "name": f"{'+'.join(c.steps[x].name for x in t.sources)} -> "
                        f"{'+'.join(c.steps[x].name for x in t.targets)}",
                "sources": t.sources, "targets": t.targets, "location": t.location,
            } for t in c.transitions],
        } for c in program.charts],
        "actors": [{
            "id": i.id, "name": f"{program.dataflows[i.dataflow].name}.{i.name}",
            "type": program.specs[i.spec].type_name, "dataflow": i.dataflow,
            "task": program.dataflows[i.dataflow].task, "location": i.location,
            "states": [d.id for d in items if d.actor == i.id],
        } for i in program.instances],
        "tasks": [{
            "id": t.id, "name": t.name, "period_us": t.period * tick, "offset_us": t.offset * tick,
            "deadline_us": t.deadline * tick, "location": t.location,
        } for t in program.tasks],
    }


def produce(program: Program, board, env, view, release: bool) -> dict[str, str]:
    """A producer of render.PRODUCERS: nothing for a release build."""
    if release:
        return {}
    enabled = has_debug_interface(program)
    items = debug_items(program, view) if enabled else []
    sizes = ""
    small = bool(getattr(board, "model_sized_debug_buffers", False))  # BoardBase's; False for a board without it
    forces, conditions = debug_slots(program, bool(getattr(board, "debug_slots_on_request", small)))
    if enabled and small:
        b = buffer_sizes(program, items, len(view.instance_states), forces, conditions)
        sizes = (f"/* The server's buffers sized from the model (docs/protocol.md: HELLO reports them): */\n"
                 f"#define EL_DBG_FRAME {b.frame}u /* its largest frame */\n"
                 f"#define EL_DBG_VALUE_BYTES {b.value}u /* its largest element */\n"
                 f"#define EL_DBG_TX_ENTRIES {b.tx}u /* a transaction's entries */\n"
                 f"#define EL_DBG_WRITE_ENTRIES {b.writes}u /* single writes queued */\n"
                 f"#define EL_DBG_BP_SLOTS {b.breakpoints}u /* breakpoints */\n")
    features = _features(program, items) if enabled else ""
    if enabled:
        features += (f"/* Forced elements and conditional breakpoints (docs/protocol.md, \"Forcing\"): */\n"
                     f"#define EL_DBG_FORCE_SLOTS {forces}u\n#define EL_DBG_COND_SLOTS {conditions}u\n")
    config = ("/* Generated by EasyLab: does this debug build have a debug interface (runtime_c/el_debug.h)? */\n"
              "#ifndef EL_DEBUG_CONFIG_H\n#define EL_DEBUG_CONFIG_H\n"
              f"#define EL_DEBUG_SERVER {1 if enabled else 0}\n{features}{sizes}#endif\n")
    files = {"el_debug_config.h": config}
    if not enabled:
        return files
    protocol_version = _protocol_version(runtime_dir() / "el_debug_protocol.h")
    files["debug_tables.c"] = env.get_template("debug_tables.c.j2").render(
        m=view, items=items, ranges=[(d, _bound(d.type, d.range[0]), _bound(d.type, d.range[1]))
                                     for d in items if d.range is not None],
        protocol_version=protocol_version)
    files["debug_map.json"] = json.dumps(debug_map(program, items), indent=1) + "\n"
    return files


def _features(program: Program, items: list[DebugItem]) -> str:
    """The ``EL_DBG_HAS_`` and ``EL_DBG_RANGES_`` switches of el_debug.c:
    what this model has, so that the server leaves out the code of what it
    lacks (charts, items of several elements, range checks of each kind of
    value)."""
    ranged = [d.type for d in items if d.range is not None]
    kinds = {
        "UNSIGNED": any(not t.signed for t in ranged),
        "SIGNED": any(t.signed and t.is_integer for t in ranged),
        "FLOAT": any(t == T.FLOAT32 for t in ranged),
    }
    lines = ["/* What the model has: the server leaves out the code of what it lacks (runtime_c/el_debug.c). */",
             f"#define EL_DBG_HAS_CHARTS {1 if program.charts else 0}",
             f"#define EL_DBG_HAS_ARRAYS {1 if any(d.count > 1 for d in items) else 0}"]
    lines += [f"#define EL_DBG_RANGES_{k} {1 if v else 0}" for k, v in kinds.items()]
    return "\n".join(lines) + "\n"


def debug_slots(program: Program, small: bool) -> tuple[int, int]:
    """(forced elements, conditional breakpoints) the server has room for:
    the debug interface's ``force N`` and ``conditions N``, else none where
    slots come on request (``small``: a part short of RAM, a board that
    says so) and the protocol's most elsewhere."""
    k = protocol_constants()
    settings = next((i.settings for i in program.interfaces if i.kind == "debug"), {})
    return (settings.get("force", 0 if small else k.FORCE_MAX),
            settings.get("conditions", 0 if small else k.COND_MAX))


def _element_bytes(t: T.ValueType) -> int:
    return max(1, t.bits // 8)


def buffer_sizes(program: Program, items: list[DebugItem], actors: int, forces: int = 0,
                 conditions: int = 0) -> SimpleNamespace:
    """The debug server's buffers sized from the model, within the
    protocol's limits: ``value``, its largest element (bytes); ``tx`` and
    ``writes``, the entries of a transaction and of the queue of single
    writes (at most TX_MAX and WRITE_QUEUE, and at most one per element of
    the model's items, the charts' state aside: a transaction that touches
    every element of them once fits);
    ``breakpoints``, the slots (at most BP_MAX, and at most the model's
    probe points: the instant, its tasks, charts, steps, transitions and
    the ``actors`` instances; a point holds one slot at most);
    ``frame``, the largest decoded frame its server sends or takes: the
    largest of the responses of docs/protocol.md for this model (HELLO and
    the other fixed ones, a breakpoint list, the stack with its charts, a
    read of its largest item, a transaction's reads, the list of its
    ``forces`` forced elements), at most MAX_FRAME; its ``conditions``
    conditional breakpoints are listed with the others."""
    k = protocol_constants()
    value = max((_element_bytes(d.type) for d in items), default=1)
    # the charts' state is read-only and read by few: it does not grow the queues (a transaction that reads
    # it as well may find them full, E_QUEUE_FULL)
    elements = max(1, sum(d.count for d in items if d.kind not in CHART_KINDS))
    tx, writes = min(k.TX_MAX, elements), min(k.WRITE_QUEUE, elements)
    points = 1 + len(program.tasks) + actors + sum(1 + len(c.steps) + len(c.transitions) for c in program.charts)
    breakpoints = min(k.BP_MAX, points)
    payloads = [  # status included
        19 + (2 if forces or conditions else 0),              # HELLO (the slots, when there are)
        16,                                                   # GET_FLAGS
        2 + 2 * k.C_COUNT,                                    # GET_COUNTERS
        14,                                                   # ITEM_INFO
        2 + 8 * breakpoints + (9 + k.VALUE_MAX) * conditions,  # BP_LIST
        2 + (5 + value) * forces,                             # FORCE_LIST
        5 + value,                                            # BP_WHEN (request): id, element, op, value
        17 + sum(1 + c.slots for c in program.charts),        # GET_STACK
        1 + max((_element_bytes(d.type) * d.count for d in items), default=0),  # READ of the largest item
        2 + tx * value,                                       # TX_COMMIT, TX_RESULT: the reads
        4 + value,                                            # WRITE (request): id, element, value
    ]
    frame = min(k.MAX_FRAME, k.HEADER + max(payloads) + k.TRAILER)
    return SimpleNamespace(frame=frame, value=value, tx=tx, writes=writes, breakpoints=breakpoints)


def _protocol_version(header: Path) -> int:
    version = parse_protocol_header(header.read_text(encoding="utf-8")).get("PROTOCOL_VERSION")
    if version is None:
        raise ValueError(f"{header}: no EL_DBG_PROTOCOL_VERSION")
    return version


def interface_hook(program: Program, release: bool) -> tuple[list[str], list[str]]:
    """A hook of render.INTERFACE_HOOKS: start and serve the debug server."""
    if release or not has_debug_interface(program):
        return [], []
    return ["el_debug_boot(); /* debug interface (docs/protocol.md) */"], ["el_debug_poll();"]
