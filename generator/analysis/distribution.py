"""Links between nodes: the Modbus RTU round's timing and register table,
and when a value published on one node reaches another (docs/distribution.md).

A Modbus RTU link is a time-triggered round run by its master every
``round`` microseconds, starting at logical time 0:

1. the **sync**: a broadcast (unit 0) write of the round number (function 6,
   8 bytes), followed by a t3.5 silence and the slaves' turnaround, in which
   each slave re-aligns its tick on the round;
2. one **slot** per slave, in declaration order: a read/write multiple
   registers request (function 23, 13 + 2 W bytes) that writes the slave's
   inputs, a t3.5 silence, the slave's turnaround, its response (5 + 2 R
   bytes) that reads its outputs, and a t3.5 silence.

A character is 11 bits (start, 8 data, parity or a second stop bit, stop);
t3.5 is 3.5 characters up to 19200 baud and 1750 us above (the Modbus
serial line specification). The sync error bound E, the most a slave's
logical time differs from the master's, is two character times (the
master's start of transmission and the slave's end-of-frame detection)
plus the link's declared ``jitter`` (the master's own scheduling jitter).

A value published at logical time d by a slave is carried by the first
slot of its node that starts at or after d + E and is at the master at
that slot's end; a value for a slave is written in the first slot of that
slave that starts at or after the value is at the master, and the slave
may use it from that slot's end + E on. A channel between two slaves goes
through the master, in two slots. On a DDS link a value published at d is
available at d + latency + jitter.

Everything here is exact (microseconds as fractions) and pure: the same
figures for the checker, the round table and the tests.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from fractions import Fraction
from math import ceil

from ..core import types as T
from ..core.modbus_round import READ_BASE, SYNC_REGISTER, WRITE_BASE
from ..core.source import Diagnostics, note
from ..frontend.model import CheckedModel, LinkInfo

BITS_PER_CHARACTER = 11
FIXED_SILENCE_US = 1750  # t3.5 above 19200 baud
FIXED_SILENCE_ABOVE_BAUD = 19200
SYNC_FRAME_BYTES = 8  # unit, function 6, register (2), value (2), CRC (2)
REQUEST_BYTES = 13  # function 23 without its data: unit, function, read start and count, write start and count, byte count, CRC
RESPONSE_BYTES = 5  # function 23's response without its data: unit, function, byte count, CRC
MAX_READ_REGISTERS = 125  # function 23's limits
MAX_WRITE_REGISTERS = 121


def character_us(baud: int) -> Fraction:
    """The time of one 11-bit character at ``baud``, in microseconds."""
    return Fraction(BITS_PER_CHARACTER * 1_000_000, baud)


def silence_us(baud: int) -> Fraction:
    """t3.5, the silence that ends a frame."""
    return FIXED_SILENCE_US if baud > FIXED_SILENCE_ABOVE_BAUD else Fraction(7, 2) * character_us(baud)


def frame_us(size: int, baud: int) -> Fraction:
    return size * character_us(baud)


def registers_per_value(t: T.ValueType) -> int:
    """16-bit registers one value of type ``t`` takes (big-endian words)."""
    return 2 if t.bits > 16 else 1


@dataclass(frozen=True)
class SlotTiming:
    node: str
    unit: int
    start_us: Fraction  # from the start of the round
    request_us: Fraction
    response_us: Fraction
    length_us: Fraction
    write_registers: int
    read_registers: int


@dataclass(frozen=True)
class RoundTiming:
    baud: int
    period_us: int
    character_us: Fraction
    silence_us: Fraction
    turnaround_us: int
    sync_us: Fraction  # the sync frame, its silence and the turnaround
    slots: tuple[SlotTiming, ...]
    length_us: Fraction  # sync and slots
    error_us: Fraction  # the sync error bound E

    def slot(self, node: str) -> SlotTiming:
        return next(s for s in self.slots if s.node == node)


def round_timing(baud: int, period_us: int, turnaround_us: int, jitter_us: int,
                 slaves: list[tuple[str, int, int, int]]) -> RoundTiming:
    """The round of a Modbus RTU link: ``slaves`` are (node, unit, registers
    written, registers read) in slot order; each slot writes and reads at
    least one register (function 23 moves at least one each way)."""
    char, silence = character_us(baud), silence_us(baud)
    sync = frame_us(SYNC_FRAME_BYTES, baud) + silence + turnaround_us
    slots = []
    at = sync
    for node, unit, writes, reads in slaves:
        request = frame_us(REQUEST_BYTES + 2 * writes, baud)
        response = frame_us(RESPONSE_BYTES + 2 * reads, baud)
        length = request + silence + turnaround_us + response + silence
        slots.append(SlotTiming(node, unit, at, request, response, length, writes, reads))
        at += length
    return RoundTiming(baud, period_us, char, silence, turnaround_us, sync, tuple(slots), at,
                       2 * char + jitter_us)


def next_start(t: Fraction, offset: Fraction, period: int) -> Fraction:
    """The first time ``offset + k * period`` (k an integer) at or after ``t``."""
    return offset + period * ceil((Fraction(t) - offset) / period)


# ====================================================================== the round table


@dataclass(frozen=True)
class RegisterBlock:
    """A channel's registers in a slot: ``tokens`` values of ``per_value``
    registers each, from ``offset`` in the slot's read or write block."""

    channel: str
    offset: int
    registers: int
    tokens: int
    per_value: int
    # Values the slot carries in round r: counts[r] up to the end, then the
    # counts from repeat_from on again (see carry_counts).
    counts: tuple[int, ...] = ()
    repeat_from: int = 0

    def carried(self, round_number: int) -> int:
        """How many values this block carries in round ``round_number``."""
        if round_number < len(self.counts):
            return self.counts[round_number]
        cycle = len(self.counts) - self.repeat_from
        return self.counts[self.repeat_from + (round_number - self.repeat_from) % cycle]


@dataclass(frozen=True)
class SlotTable:
    node: str
    unit: int
    uart: str
    writes: tuple[RegisterBlock, ...]  # the master writes them: the slave's inputs
    reads: tuple[RegisterBlock, ...]  # the master reads them: the slave's outputs (after the status register)


@dataclass(frozen=True)
class RoundTable:
    """A Modbus link's round as data: slot order, registers per slave and
    their offsets, and the round's timing."""

    link: str
    master: str
    slots: tuple[SlotTable, ...]
    timing: RoundTiming


@dataclass(frozen=True)
class Carriage:
    """How a channel crosses a link: its nodes and the round or DDS figures
    that give each value's arrival."""

    channel: str
    link: str
    producer_node: str
    consumer_node: str
    round: RoundTiming | None  # a Modbus link's round
    master: str | None
    dds_delay_us: int = 0  # a DDS link's latency + jitter

    def arrival(self, published_us) -> Fraction:
        """When a value published at ``published_us`` (logical time) may be
        used on the consumer's node."""
        d = Fraction(published_us)
        if self.round is None:
            return d + self.dds_delay_us
        r = self.round
        at_master = d
        if self.producer_node != self.master:
            slot = r.slot(self.producer_node)
            at_master = next_start(d + r.error_us, slot.start_us, r.period_us) + slot.length_us
        if self.consumer_node == self.master:
            return at_master
        slot = r.slot(self.consumer_node)
        return next_start(at_master, slot.start_us, r.period_us) + slot.length_us + r.error_us


@dataclass
class LinkPlan:
    rounds: dict[str, RoundTable]
    carriages: dict[str, Carriage]  # channel name -> how it crosses its link


def _tokens_per_round(round_us: int, period_us, tokens: int) -> int:
    """The most values a producer of ``period_us`` publishes within one round."""
    return ceil(Fraction(round_us) / Fraction(period_us)) * tokens


def carry_counts(timing: RoundTiming, carriage: Carriage, slot_node: str, first_us, period_us,
                 tokens: int) -> tuple[tuple[int, ...], int]:
    """The values a slot of ``slot_node`` carries in each round, for a
    producer that publishes ``tokens`` values at ``first_us + k *
    period_us``: (counts, repeat_from), the counts of rounds 0, 1, ...
    whose tail from ``repeat_from`` on repeats. A value from a slave is
    carried by the first slot of its node that starts at or after its
    publication + E; a value for a slave by the first slot of that slave
    that starts at or after the value is at the master (Carriage.arrival)."""
    period_us, first_us = Fraction(period_us), Fraction(first_us)
    slot = timing.slot(slot_node)
    cycle = int(_lcm_fraction(Fraction(timing.period_us), period_us) / timing.period_us)
    rounds: dict[int, int] = {}
    first_round = None
    k = 0
    while True:
        d = first_us + k * period_us
        if slot_node == carriage.producer_node:  # read from the producer
            start = next_start(d + timing.error_us, slot.start_us, timing.period_us)
        else:  # written to the consumer, once at the master
            at_master = d
            if carriage.producer_node != carriage.master:
                src = timing.slot(carriage.producer_node)
                at_master = next_start(d + timing.error_us, src.start_us, timing.period_us) + src.length_us
            start = next_start(at_master, slot.start_us, timing.period_us)
        r = int((start - slot.start_us) / timing.period_us)
        first_round = r if first_round is None else first_round
        if r >= first_round + 3 * cycle:
            break
        rounds[r] = rounds.get(r, 0) + tokens
        k += 1
    repeat_from = first_round + cycle
    counts = tuple(rounds.get(r, 0) for r in range(repeat_from + cycle))
    return counts, repeat_from


def _lcm_fraction(a: Fraction, b: Fraction) -> Fraction:
    """The least common multiple of two positive rationals."""
    from math import gcd
    num = a.numerator * b.denominator, b.numerator * a.denominator
    den = a.denominator * b.denominator
    return Fraction(num[0] * num[1] // gcd(num[0], num[1]), den)


def plan_links(model: CheckedModel, diags: Diagnostics) -> LinkPlan | None:
    """Each Modbus link's round table and each cross-node channel's
    carriage, after the SDF analysis; None after errors (a round that
    cannot carry its channels)."""
    plan = LinkPlan({}, {})
    ok = True
    for link in model.links.values():
        crossing = [ch for ch in model.channels.values() if ch.link is link]
        if link.engine == "dds":
            delay = link.settings["latency"] + link.settings["jitter"]
            for ch in crossing:
                p, c = _ends(model, ch)
                plan.carriages[ch.name] = Carriage(ch.name, link.name, p, c, None, None, delay)
            continue
        table = _round_table(model, link, crossing, diags)
        if table is None:
            ok = False
            continue
        plan.rounds[link.name] = table
        for ch in crossing:
            p, c = _ends(model, ch)
            plan.carriages[ch.name] = Carriage(ch.name, link.name, p, c, table.timing, table.master)
    return plan if ok else None


def _ends(model: CheckedModel, ch) -> tuple[str, str]:
    return _node(model, ch.producers[0]), _node(model, ch.consumers[0])


def _node(model: CheckedModel, edge) -> str:
    df = next(df for df in model.dataflows.values() if edge in df.edges)
    return model.task_nodes[df.task.name]


def _round_table(model: CheckedModel, link: LinkInfo, crossing: list, diags: Diagnostics) -> RoundTable | None:
    master = next(m.node.name for m in link.members if m.role == "master")
    slaves = [m for m in link.members if m.role == "slave"]
    writes: dict[str, list[RegisterBlock]] = {m.node.name: [] for m in slaves}
    reads: dict[str, list[RegisterBlock]] = {m.node.name: [] for m in slaves}
    period = link.settings["round"]
    for ch in crossing:
        p_node, c_node = _ends(model, ch)
        df = next(df for df in model.dataflows.values() if ch.producers[0] in df.edges)
        per_activation = df.analysis.result.repetitions["out:" + ch.name]
        tokens = _tokens_per_round(period, df.task.period_us, per_activation)
        per_value = registers_per_value(ch.type)
        if p_node != master:
            block = reads[p_node]
            offset = 1 + sum(b.registers for b in block)  # after the status register
            block.append(RegisterBlock(ch.name, offset, tokens * per_value, tokens, per_value))
        if c_node != master:
            block = writes[c_node]
            offset = sum(b.registers for b in block)
            block.append(RegisterBlock(ch.name, offset, tokens * per_value, tokens, per_value))
    ok = True
    for m in slaves:
        node = m.node.name
        w = sum(b.registers for b in writes[node])
        r = 1 + sum(b.registers for b in reads[node])
        for count, limit, what, blocks in ((w, MAX_WRITE_REGISTERS, "written to", writes[node]),
                                           (r, MAX_READ_REGISTERS, "read from", reads[node])):
            if count > limit:
                names = ", ".join(f"'{b.channel}' ({b.registers})" for b in blocks)
                diags.error(link.decl.name_span, f"link '{link.name}' cannot carry its channels: {count} registers "
                                                 f"{what} node '{node}' in one slot, more than function 23's "
                                                 f"{limit} ({names})",
                            "carry fewer or smaller values, or shorten the round",
                            [note(m.decl.span, f"node '{node}' is on the link here")])
                ok = False
    if not ok:
        return None
    timing = round_timing(link.settings["baud"], period, link.settings["turnaround"], link.settings["jitter"],
                          [(m.node.name, m.unit, max(1, sum(b.registers for b in writes[m.node.name])),
                            1 + sum(b.registers for b in reads[m.node.name])) for m in slaves])
    if timing.length_us > period:
        parts = ", ".join([f"sync {_us(timing.sync_us)}"] + [f"slot of '{s.node}' {_us(s.length_us)}"
                                                               for s in timing.slots])
        diags.error(link.decl.name_span, f"the round of link '{link.name}' takes {_us(timing.length_us)} ({parts}) "
                                         f"at {timing.baud} baud, longer than its period of {_us(period)}: it "
                                         "cannot carry its channels",
                    "lengthen the round, raise the baud rate or carry fewer values")
        return None
    producers = {}
    for ch in crossing:
        df = next(df for df in model.dataflows.values() if ch.producers[0] in df.edges)
        producers[ch.name] = (df.task.offset_us + df.task.deadline_us, df.task.period_us,
                              df.analysis.result.repetitions["out:" + ch.name], Carriage(
                                  ch.name, link.name, *_ends(model, ch), timing, master))

    def scheduled(node: str, blocks: list[RegisterBlock]) -> tuple[RegisterBlock, ...]:
        out = []
        for b in blocks:
            first, period, tokens, carriage = producers[b.channel]
            counts, repeat_from = carry_counts(timing, carriage, node, first, period, tokens)
            out.append(replace(b, counts=counts, repeat_from=repeat_from))
        return tuple(out)

    slots = tuple(SlotTable(m.node.name, m.unit, str(m.uart), scheduled(m.node.name, writes[m.node.name]),
                            scheduled(m.node.name, reads[m.node.name])) for m in slaves)
    return RoundTable(link.name, master, slots, timing)


def round_summary(table: RoundTable) -> dict:
    """The round table as JSON-ready data (times in µs, two decimals)."""
    t = table.timing

    def blocks(items, base):
        return [{"channel": b.channel, "register": base + b.offset, "registers": b.registers, "values": b.tokens}
                for b in items]

    return {
        "link": table.link, "master": table.master, "baud": t.baud, "period_us": t.period_us,
        "character_us": _two(t.character_us), "silence_us": _two(t.silence_us), "turnaround_us": t.turnaround_us,
        "sync_us": _two(t.sync_us), "length_us": _two(t.length_us), "sync_error_us": _two(t.error_us),
        "slots": [{"node": s.node, "unit": s.unit, "uart": s.uart, "start_us": _two(timing.start_us),
                   "length_us": _two(timing.length_us), "writes": blocks(s.writes, WRITE_BASE),
                   "reads": blocks(s.reads, READ_BASE)} for s, timing in zip(table.slots, t.slots)],
    }


def render_round(table: RoundTable) -> str:
    """The round table as text, for ``easylab analyze``."""
    t = table.timing
    lines = [f"link {table.link} (Modbus RTU, master {table.master}): a round every {t.period_us} us at {t.baud} "
             f"baud takes {_two(t.length_us)} us",
             f"  character {_two(t.character_us)} us, t3.5 {_two(t.silence_us)} us, turnaround {t.turnaround_us} us, "
             f"sync error {_two(t.error_us)} us",
             f"  sync                 0.00 us  +{_two(t.sync_us)} us  broadcast round number to 0x{SYNC_REGISTER:04X}"]
    for s, timing in zip(table.slots, t.slots):
        writes = ", ".join(f"{b.channel} 0x{WRITE_BASE + b.offset:04X} ({b.registers})" for b in s.writes) \
            or f"round number 0x{WRITE_BASE:04X} (1)"
        reads = ", ".join([f"status 0x{READ_BASE:04X} (1)"] + [f"{b.channel} 0x{READ_BASE + b.offset:04X} "
                                                              f"({b.registers})" for b in s.reads])
        lines.append(f"  slot {s.node} (unit {s.unit}, {s.uart})  {_two(timing.start_us)} us  +{_two(timing.length_us)} us"
                     f"  writes {writes}; reads {reads}")
    return "\n".join(lines) + "\n"


def _two(value) -> float:
    return round(float(value), 2)


def _us(value) -> str:
    """Microseconds for messages, rounded up to a whole microsecond."""
    return f"{ceil(Fraction(value))} us"


def worst_latency_us(carriage: Carriage, publications) -> int:
    """The longest time, in whole microseconds rounded up, from a
    publication in ``publications`` to its arrival."""
    return max((ceil(carriage.arrival(d) - d) for d in publications), default=0)


__all__ = ["Carriage", "LinkPlan", "RegisterBlock", "carry_counts", "RoundTable", "RoundTiming", "SlotTable", "SlotTiming", "character_us",
           "frame_us", "next_start", "plan_links", "registers_per_value", "render_round", "round_summary", "round_timing",
           "silence_us",
           "worst_latency_us"]
