"""The C of a node's Modbus round (docs/distribution.md, "The round at run
time"): el_link.c, from the round table the IR carries. The master sends
the sync and one function-23 exchange per slot at their logical times; a
slave answers them and lets its ticks run up to its slot on each sync.
Which values each slot carries in each round is the round table's
(``RegisterBlock.counts``): nothing about timing is decided here."""

from __future__ import annotations

from dataclasses import dataclass
from math import floor

from ..core import types as T
from ..core.errors import BuildError
from ..core.modbus_round import READ_BASE, SYNC_REGISTER, WRITE_BASE
from ..ir.split import NodeProgram

@dataclass
class BlockView:
    """One channel's registers in a slot, as the C tables print them."""

    index: int
    channel_id: int  # the channel's id in the node's program
    name: str
    c_type: str
    offset: int
    tokens: int
    per_value: int
    counts: list[int]
    repeat_from: int
    pulled: bool  # this node takes the values from the channel's output end (else it pushes them in)
    pack: str  # C statement: value v[i] into regs[...]
    unpack: str  # C expression: regs[...] as a value


def _pack(t: T.ValueType) -> tuple[str, str]:
    """Big-endian registers of one value ``v[i]`` at ``regs + i * per``."""
    if t.bits > 16:
        if t.c_name == "float":
            return ("{ union { float f; uint32_t u; } w; w.f = v[i]; p[0] = (uint16_t)(w.u >> 16); "
                    "p[1] = (uint16_t)(w.u & 0xFFFFu); }",
                    "el_lk_float(p)")
        return ("p[0] = (uint16_t)((uint32_t)v[i] >> 16); p[1] = (uint16_t)((uint32_t)v[i] & 0xFFFFu);",
                f"({t.c_name})(((uint32_t)p[0] << 16) | (uint32_t)p[1])")
    if t.name == "bool":
        return "p[0] = v[i] ? 1u : 0u;", "(p[0] != 0u)"
    if t.signed:
        back = f"({t.c_name})p[0]" if t.bits == 16 else f"({t.c_name})(int16_t)p[0]"
        return "p[0] = (uint16_t)(int16_t)v[i];", back
    return "p[0] = (uint16_t)v[i];", f"({t.c_name})p[0]"


def link_files(node: NodeProgram) -> dict[str, str]:
    """el_link.c of a node on a Modbus link; {} for a node on none. A node on
    two Modbus links, and a channel between two slaves (relayed by the
    master), are not built yet (BuildError)."""
    from .render import environment

    if not node.rounds:
        return {}
    if len(node.rounds) > 1:
        raise BuildError(f"node '{node.node.name}' is on {len(node.rounds)} Modbus links: a node on one link "
                         "only is built yet (docs/distribution.md)")
    table = node.rounds[0]
    program = node.program
    ids = {c.name: c for c in program.channels}
    blocks: list[BlockView] = []

    master = table.master == node.node.name

    def view(b, written: bool) -> BlockView:
        ch = ids.get(b.channel)
        if ch is None:
            raise BuildError(f"channel '{b.channel}' goes between two slaves of link '{table.link}': relaying it "
                             "through the master is not built yet (docs/distribution.md)")
        if max(b.counts) > b.tokens:  # the C copies at most `tokens` values a slot
            raise BuildError(f"channel '{b.channel}': the round table carries {max(b.counts)} values in one slot, "
                             f"more than its block's {b.tokens}")
        pack, unpack = _pack(ch.type)
        v = BlockView(len(blocks), ch.id, ch.name, ch.type.c_name, b.offset, b.tokens, b.per_value,
                      list(b.counts), b.repeat_from, written == master, pack, unpack)
        blocks.append(v)
        return v

    timing = table.timing
    slots = []
    for s, st in zip(table.slots, timing.slots):
        if not master and s.node != node.node.name:
            continue
        slots.append({"node": s.node, "unit": s.unit, "start_us": floor(st.start_us),
                      "writes": [view(b, True) for b in s.writes], "reads": [view(b, False) for b in s.reads],
                      "w": st.write_registers, "r": st.read_registers})
    env = environment()
    text = env.get_template("link.c.j2").render(
        node=node.node.name, program=program, master=master, slots=slots, blocks=blocks,
        link=table.link, period_us=timing.period_us, tick_us=program.tick_us,
        sync_register=SYNC_REGISTER, read_base=READ_BASE, write_base=WRITE_BASE)
    return {"el_link.c": text}


def link_defines(node: NodeProgram) -> list[str]:
    """The C flags that turn on a node's side of its round in the port and
    the Modbus slave (EL_ROUND_MASTER, EL_ROUND_SLAVE); none for a node on
    no Modbus link, whose firmware has no trace of a round."""
    if not node.rounds:
        return []
    return ["-DEL_ROUND_MASTER=1" if node.rounds[0].master == node.node.name else "-DEL_ROUND_SLAVE=1"]


__all__ = ["link_defines", "link_files"]
