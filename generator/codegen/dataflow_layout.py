"""How a dataflow's code reaches its buffers (DataflowLayout), and the
code of a long schedule over circular buffers as a table (c_model.py's
builder fires each node)."""

from __future__ import annotations

from dataclasses import dataclass

from ..ir.program import Dataflow, Fire


@dataclass
class DataflowLayout:
    """Where a dataflow's buffers are and how its schedule reaches them."""

    df: Dataflow
    linear: bool  # single-appearance: offsets are affine in the loop counters
    bufs: dict[int, dict]  # buffer id -> its C name, size, loop level
    paths: dict[str, list]  # node -> the loops above it
    fire_nodes: dict[str, Fire]
    insts: dict[str, object]  # instance name -> ActorInstance
    exts: dict[str, object]  # external node -> External
    item_ref: object  # how an expression reaches an item: the task's local copy


def table_schedule(builder, runs: list[tuple[str, int]], layout: DataflowLayout) -> list[str]:
    """A long schedule with circular buffers (min-buffer) as data: its
    run-length firing sequence in a ROM table of (node, count) pairs
    walked by a loop around one switch over the nodes. The firing
    order is the schedule's, so the values are the same; the code is
    the size of one firing per node instead of one per appearance."""
    nodes = list(dict.fromkeys(actor for actor, _ in runs))
    pairs: list[tuple[int, int]] = []
    for actor, count in runs:
        while count > 0:
            pairs.append((nodes.index(actor), min(count, 255)))
            count -= 255
    index_t = "uint16_t" if len(pairs) <= 0xFFFF else "uint32_t"
    small = len(nodes) <= 256
    elem_t, read = ("uint8_t", "EL_ROM_READ_U8") if small else ("uint16_t", "EL_ROM_READ_U16")
    lines = [f"    static const {elem_t} el_seq[{2 * len(pairs)}] EL_ROM = {{ /* (node, firings) */"]
    flat = [v for pair in pairs for v in pair]
    for k in range(0, len(flat), 16):
        lines.append("        " + ", ".join(f"{v}u" for v in flat[k:k + 16]) + ",")
    lines.append("    };")
    lines += [f"    {index_t} el_k;", "    uint8_t el_n;",
              f"    for (el_k = 0u; el_k < {len(pairs)}u; el_k++) {{",
              f"        {elem_t} el_node = {read}(&el_seq[2u * el_k]);",
              f"        uint8_t el_times = (uint8_t){read}(&el_seq[2u * el_k + 1u]);",
              "        for (el_n = 0u; el_n < el_times; el_n++) {",
              "            switch (el_node) {"]
    for i, node in enumerate(nodes):
        lines.append(f"            case {i}u:")
        builder.fire_one(layout, node, None, "                ", lines)
        lines.append("                break;")
    lines += ["            default: break;", "            }", "        }", "    }"]
    return lines
