"""The service interface's register map (docs/service.md).

From the IR's ``service`` items this module builds the Modbus register map
and writes it beside the firmware: ``service_map.json`` (for tools, e.g.
``easylab-service``), ``service_map.csv``, ``service_map.md`` and the C
tables ``service_tables.c`` (templates/service_tables.c.j2) that the
runtime's slave and local service API (runtime_c/el_service.h) walk. It
also gives the C glue that starts the slave, polls it and loads persisted
params at boot (``interface_hook``). Both are registered in
``render.PRODUCERS`` and ``render.INTERFACE_HOOKS``.

Tables: bool items are coils (``rw``) or discrete inputs (``ro``); other
items holding registers (``rw``) or input registers (``ro``). 8- and
16-bit items take one register, 32-bit integers, ``time`` (milliseconds)
and ``float32`` two, high word first. Each table is addressed on its own,
from 0: explicit addresses (``service rw @ 100``) are placed first, then
the other items in declaration order, each at the lowest free address at or
after the end of the previous automatic one, so adding an item at the end
never moves the others.
"""

from __future__ import annotations

import csv
import io
import json
import re
import struct
from dataclasses import dataclass

from .. import __version__
from ..core import types as T
from .c_syntax import c_string
from ..core.crc import crc16  # persist keys are CRCs of the item's name and type
from ..core.errors import BuildError
from ..ir.program import Item, Program

MAP_FORMAT = 1
TABLES = ("coil", "discrete", "holding", "input")
C_TABLES = {"coil": "EL_SVC_COIL", "discrete": "EL_SVC_DISCRETE", "holding": "EL_SVC_HOLDING",
            "input": "EL_SVC_INPUT"}
C_TYPES = {"bool": "EL_T_BOOL", "int8": "EL_T_I8", "uint8": "EL_T_U8", "int16": "EL_T_I16", "uint16": "EL_T_U16",
           "int32": "EL_T_I32", "uint32": "EL_T_U32", "float32": "EL_T_F32", "time": "EL_T_TIME"}
# Conventional Modbus references (mbpoll's 1-based numbering: 00001, 10001, 40001, 30001).
REF_PREFIX = {"coil": 0, "discrete": 1, "holding": 4, "input": 3}
PERSIST_SLOT_BYTES = 20  # two records of 10 bytes (runtime_c/el_persist.h)
PARITY = {"none": "EL_MB_PARITY_NONE", "even": "EL_MB_PARITY_EVEN", "odd": "EL_MB_PARITY_ODD"}


class ServiceMapError(ValueError):
    """A register map that cannot be built (an address clash, a full table);
    the message is one line naming the items involved."""




registers_of = T.register_count  # the rule lives in types.py, shared with the checker


@dataclass
class Entry:
    """One item of the register map."""

    id: int  # map id: index in declaration order
    item: Item
    table: str
    address: int
    registers: int
    nv_slot: int | None
    nv_key: int | None

    @property
    def name(self) -> str:
        return self.item.name

    @property
    def access(self) -> str:
        return self.item.service

    def unit(self) -> str | None:
        if self.item.unit is not None:
            return self.item.unit
        return "ms" if self.item.type is T.TIME else None

    def to_json(self) -> dict:
        it = self.item
        return {
            "id": self.id, "name": it.name, "kind": it.kind, "table": self.table, "address": self.address,
            "registers": self.registers, "type": it.type.name, "scale": T.scale_number(it.scale), "unit": self.unit(),
            "range": list(it.range) if it.range is not None else None, "access": it.service,
            "persist": it.persist, "initial": it.initial, "location": it.location,
        }


@dataclass
class ServiceMap:
    program: Program
    entries: list[Entry]
    nv_count: int

    def table(self, name: str) -> list[Entry]:
        return sorted((e for e in self.entries if e.table == name), key=lambda e: e.address)

    @property
    def rtu(self):
        return next((i for i in self.program.interfaces if i.kind == "modbus-rtu"), None)

    @property
    def tcp(self):
        return next((i for i in self.program.interfaces if i.kind == "modbus-tcp"), None)


def table_of(item: Item) -> str:
    return T.register_table(item.type, item.service)


def _describe(e: Entry, located: bool = True) -> str:
    last = e.address + e.registers - 1
    where = f"{e.address}" if last == e.address else f"{e.address}..{last}"
    return f"'{e.name}' ({e.table} {where}{', ' + e.item.location if located else ''})"


def build_map(program: Program, nv_size: int | None = None) -> ServiceMap:
    """The register map of a program; ServiceMapError on a clash."""
    # The model's service items, then its status items (input registers; docs/ir.md, "Status items").
    items = [i for i in program.items if i.service is not None] + list(program.status)
    entries: list[Entry] = []
    slot = 0
    for index, item in enumerate(items):
        nv_slot = nv_key = None
        if item.persist:
            nv_slot, nv_key = slot, crc16(f"{item.name}:{item.type.name}".encode())
            slot += 1
        entries.append(Entry(index, item, table_of(item), -1, registers_of(item.type), nv_slot, nv_key))
    for table in TABLES:
        mine = [e for e in entries if e.table == table]
        placed: list[Entry] = []
        for e in mine:
            if e.item.address is None:
                continue
            e.address = e.item.address
            if e.address + e.registers - 1 > 0xFFFF:
                raise ServiceMapError(f"{e.item.location}: register address {e.address} of '{e.name}' "
                                      f"({e.item.type.name}, {e.registers} registers) runs past 65535")
            for other in placed:
                if e.address < other.address + other.registers and other.address < e.address + e.registers:
                    raise ServiceMapError(f"{e.item.location}: register address clash: {_describe(e, False)} "
                                          f"overlaps {_describe(other)}")
            placed.append(e)
        cursor = 0
        for e in mine:
            if e.item.address is not None:
                continue
            moved = True
            while moved:
                moved = False
                for other in placed:
                    if cursor < other.address + other.registers and other.address < cursor + e.registers:
                        cursor = other.address + other.registers
                        moved = True
            if cursor + e.registers - 1 > 0xFFFF:
                raise ServiceMapError(f"{e.item.location}: no register address left for '{e.name}' "
                                      f"in the {table} table")
            e.address = cursor
            cursor += e.registers
            placed.append(e)
    if nv_size is not None and slot * PERSIST_SLOT_BYTES > nv_size:
        raise ServiceMapError(f"{slot} persist params need {slot * PERSIST_SLOT_BYTES} bytes of non-volatile "
                              f"storage; the board has {nv_size}")
    return ServiceMap(program, entries, slot)


# ====================================================================== map files


def map_json(smap: ServiceMap) -> dict:
    p = smap.program
    interfaces = {}
    if smap.rtu is not None:
        interfaces["rtu"] = {"uart": smap.rtu.resource, **smap.rtu.settings}
    if smap.tcp is not None:
        interfaces["tcp"] = dict(smap.tcp.settings)
    return {
        "format": MAP_FORMAT,
        "model": p.name,
        "title": p.title,
        "program_id": f"0x{p.program_id:08x}",
        "easylab": __version__,
        "identification": {"vendor": "EasyLab", "product_code": p.name, "revision": __version__,
                           "product_name": p.title or p.name, "model_name": p.name,
                           "program_id": f"0x{p.program_id:08x}"},
        "word_order": "big",
        "encoding": "registers are big-endian 16-bit words; 32-bit values (int32, uint32, time, float32) take "
                    "two registers, the high word first at the lower address; int8 is sign-extended; "
                    "float32 as IEEE 754 bits; bool items are coils (rw) or discrete inputs (ro)",
        "interfaces": interfaces,
        "items": [e.to_json() for e in smap.entries],
    }


def map_csv(smap: ServiceMap) -> str:
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["id", "name", "table", "address", "registers", "type", "scale", "unit", "min", "max", "access",
                "persist", "initial"])
    for e in smap.entries:
        lo, hi = e.item.range if e.item.range is not None else ("", "")
        w.writerow([e.id, e.name, e.table, e.address, e.registers, e.item.type.name, e.item.scale or 1,
                    e.unit() or "", lo, hi,
                    e.access, "yes" if e.item.persist else "no", e.item.initial])
    return out.getvalue()


def _md(text) -> str:
    return str(text).replace("|", "\\|")


def _scale_note(e: Entry) -> str:
    return f" (x {e.item.scale})" if e.item.scale else ""


def map_md(smap: ServiceMap) -> str:
    p = smap.program
    lines = [f"# Service map of model `{p.name}`", ""]
    if p.title:
        lines += [p.title, ""]
    lines += [f"Program id `0x{p.program_id:08x}`, generated by EasyLab {__version__}.", ""]
    if smap.rtu is not None:
        s = smap.rtu.settings
        lines.append(f"- Modbus RTU on {smap.rtu.resource}: {s['baud']} baud, parity {s['parity']}, unit {s['unit']}")
    if smap.tcp is not None:
        lines.append(f"- Modbus TCP on port {smap.tcp.settings['port']} (any unit id is answered)")
    lines += ["- Addresses are PDU addresses from 0; the reference column is the conventional 1-based "
              "number (mbpoll: `-r` takes address + 1).",
              "- 32-bit values (int32, uint32, time, float32) take two registers, the high word first.",
              "- `rw` items are written with 05/15 (coils) or 06/16 (holding registers; a 32-bit item only "
              "with 16 over both of its registers); a value outside the range gives exception 03.",
              "- Registers hold values in stored units: an item shown `(x 0.1)` holds its engineering value "
              "divided by 0.1 (register 1628 is 162.8); its range is in stored units too.", ""]
    if not smap.entries:
        lines += ["The model has no `service` items.", ""]
        return "\n".join(lines)
    lines += ["| id | name | table | address | reference | type | unit | range | access | persist |",
              "|---:|---|---|---:|---|---|---|---|---|---|"]
    for e in smap.entries:
        ref = f"{REF_PREFIX[e.table]}{e.address + 1:05d}"
        if e.registers == 2:
            ref += f"..{REF_PREFIX[e.table]}{e.address + 2:05d}"
        rng = f"{e.item.range[0]}..{e.item.range[1]}" if e.item.range is not None else ""
        lines.append(f"| {e.id} | `{_md(e.name)}` | {e.table} | {e.address} | {ref} | {e.item.type.name} | "
                     f"{_md(e.unit() or '')}{_scale_note(e)} | {rng} | {e.access} | {'yes' if e.item.persist else ''} |")
    lines.append("")
    return "\n".join(lines)


# ====================================================================== C tables


def _bits(t: T.ValueType, value) -> str:
    """A range bound as the 32-bit pattern el_svc_entry_t holds."""
    if t is T.FLOAT32:
        pattern = struct.unpack("<I", struct.pack("<f", float(value)))[0]
    else:
        pattern = int(value) & 0xFFFFFFFF
    return f"0x{pattern:08x}UL"


def _uart_index(resource: str | None) -> int:
    m = re.search(r"(\d+)", resource or "")
    return int(m.group(1)) if m else 0


def c_view(smap: ServiceMap, view, service_api: bool = False) -> dict:
    """What templates/service_tables.c.j2 prints. The map itself (its
    entries, the persist state, el_service_init at boot) only when something
    uses it: a Modbus interface, a persist param (loaded at boot), or the
    board's own code (``service_api``); otherwise a firmware links none of
    the service layer."""
    p = smap.program
    items_by_id = {iv.item.id: iv for iv in view.items}
    status_by_id = {sv.item.id: sv for sv in view.status}
    entries = []
    for e in smap.entries:
        if e.item.kind == "status":
            iv = status_by_id[e.item.id]
            c_extern = iv.c_extern
        else:
            iv = items_by_id[e.item.id]
            c_extern = f"extern {iv.c_type} {iv.c_name};"
        flags = ["EL_SVC_F_RW" if e.access == "rw" else None, "EL_SVC_F_PERSIST" if e.item.persist else None,
                 "EL_SVC_F_RANGE" if e.item.range is not None else None]
        flags = " | ".join(f for f in flags if f) or "0u"
        lo, hi = (_bits(e.item.type, e.item.range[0]), _bits(e.item.type, e.item.range[1])) \
            if e.item.range is not None else ("0UL", "0UL")
        entries.append({
            "e": e, "c_name": iv.c_name, "c_extern": c_extern, "name": c_string(e.name), "lo": lo, "hi": hi,
            "type": C_TYPES[e.item.type.name], "table": C_TABLES[e.table], "flags": flags,
            "nv_key": f"0x{e.nv_key:04x}u" if e.nv_key is not None else "0u",
            "nv_slot": f"{e.nv_slot}u" if e.nv_slot is not None else "0u",
        })
    order, first, size = [], [], []
    for table in TABLES:
        first.append(len(order))
        rows = smap.table(table)
        size.append(len(rows))
        order.extend(e.id for e in rows)
    rtu = tcp = None
    if smap.rtu is not None:
        s = smap.rtu.settings
        rtu = {"uart": _uart_index(smap.rtu.resource), "baud": s["baud"], "parity": PARITY[s["parity"]],
               "unit": s["unit"], "resource": smap.rtu.resource}
    if smap.tcp is not None:
        tcp = {"port": smap.tcp.settings["port"]}
    return {
        "version": __version__, "program": p, "entries": entries, "order": order, "first": first, "size": size,
        "nv_count": smap.nv_count, "vendor": c_string("EasyLab"), "model": c_string(p.name),
        "title": c_string(p.title or p.name), "easylab": c_string(__version__),
        "program_text": c_string(f"0x{p.program_id:08x}"), "program_id": f"0x{p.program_id:08x}UL",
        "rtu": rtu, "tcp": tcp,
        "map_used": rtu is not None or tcp is not None or smap.nv_count > 0 or service_api,
    }


# ====================================================================== the producer and the hook


def produce(program: Program, board, env, view, release: bool) -> dict[str, str]:
    """A producer of render.PRODUCERS: the map files and service_tables.c."""
    try:
        smap = build_map(program, board.nv_size)
    except ServiceMapError as err:
        raise BuildError(str(err)) from None
    service_api = bool(getattr(board, "service_api", False))  # BoardBase's; False for a board without it
    text = env.get_template("service_tables.c.j2").render(s=c_view(smap, view, service_api), release=release)
    return {
        "service_map.json": json.dumps(map_json(smap), indent=2) + "\n",
        "service_map.csv": map_csv(smap),
        "service_map.md": map_md(smap),
        "service_tables.c": text,
    }


def interface_hook(program: Program, release: bool) -> tuple[list[str], list[str]]:
    """A hook of render.INTERFACE_HOOKS: start the service interface at boot (load
    persisted params, open the Modbus links), serve it when idle."""
    boot = ["{ extern void el_svc_gen_boot(void); el_svc_gen_boot(); } /* service map, persist, Modbus */"]
    poll = ["{ extern void el_svc_gen_poll(void); el_svc_gen_poll(); } /* Modbus RTU / TCP */"]
    return boot, poll
