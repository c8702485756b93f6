"""The Modbus round's timing, each value's arrival across a link, and the
delays the checker asks for; figures computed by hand in the comments."""

from __future__ import annotations

from fractions import Fraction

from easylab.analysis.distribution import (Carriage, character_us, frame_us, next_start, registers_per_value,
                                           round_timing, silence_us)
from easylab.core import types as T
from easylab.pipeline import check_file
from distribution_testlib import ROBOT, position, variant

CHAR = Fraction(11_000_000, 115200)  # 95.486 us: 11 bits at 115200 baud


def test_character_and_silence_times():
    assert character_us(115200) == CHAR == Fraction(6875, 72)
    assert silence_us(115200) == 1750  # fixed above 19200 baud
    assert silence_us(19200) == Fraction(7, 2) * Fraction(11_000_000, 19200)  # 2005.2 us: 3.5 characters
    assert silence_us(9600) == Fraction(7, 2) * Fraction(11_000_000, 9600)
    assert frame_us(8, 115200) == 8 * CHAR


def test_registers_per_value():
    assert [registers_per_value(t) for t in (T.BOOL, T.INT8, T.UINT16, T.INT16, T.INT32, T.FLOAT32, T.TIME)] == \
        [1, 1, 1, 1, 2, 2, 2]


def two_slaves():
    # j1: one int16 written, one int32 read (+ the status register): W = 1, R = 3
    # j2: one int16 written, nothing read (the status register only): W = 1, R = 1
    return round_timing(115200, 20000, 1000, 0, [("j1", 2, 1, 3), ("j2", 3, 1, 1)])


def test_two_slaves_at_115200_baud():
    r = two_slaves()
    # sync: 8 characters, t3.5, turnaround = 763.89 + 1750 + 1000 = 3513.89 us
    assert r.sync_us == 8 * CHAR + 1750 + 1000 == Fraction(31625, 9)
    j1, j2 = r.slots
    # j1: request 13 + 2 bytes, t3.5, turnaround, response 5 + 6 bytes, t3.5 = 6982.64 us
    assert (j1.request_us, j1.response_us) == (15 * CHAR, 11 * CHAR)
    assert j1.start_us == r.sync_us
    assert j1.length_us == 26 * CHAR + 2 * 1750 + 1000 == Fraction(251375, 36)
    # j2: request 15 bytes, response 5 + 2 bytes = 6600.69 us
    assert j2.start_us == r.sync_us + j1.length_us
    assert j2.length_us == 22 * CHAR + 2 * 1750 + 1000 == Fraction(237625, 36)
    assert r.length_us == r.sync_us + j1.length_us + j2.length_us
    assert round(float(r.length_us), 2) == 17097.22
    assert r.error_us == 2 * CHAR  # 190.97 us


def test_next_start_of_a_slot():
    assert next_start(Fraction(20000), Fraction(3500), 20000) == 23500
    assert next_start(Fraction(3500), Fraction(3500), 20000) == 3500
    assert next_start(Fraction(3501), Fraction(3500), 20000) == 23500


def test_arrivals_through_the_round():
    r = two_slaves()
    j1, j2 = r.slots
    e = r.error_us
    down = Carriage("goal1", "bus", "pc", "j1", r, "pc")
    # written in j1's slot of the next round, usable from its end + E: 30687.5 us
    assert down.arrival(20000) == 20000 + j1.start_us + j1.length_us + e
    assert float(down.arrival(20000)) == 30687.5
    up = Carriage("pos1", "bus", "j1", "pc", r, "pc")
    # read in the first j1 slot that starts E after the publication: at the master at its end
    assert up.arrival(20000) == 20000 + j1.start_us + j1.length_us
    assert up.arrival(3000) == j1.start_us + j1.length_us  # 3000 + E is before the slot's start
    assert up.arrival(j1.start_us) == 20000 + j1.start_us + j1.length_us  # too late by E: the next round
    across = Carriage("x", "bus", "j2", "j1", r, "pc")
    # j2's slot of round 1 brings it to the master at 37097.2 us; j1's slot of round 2 takes it on
    at_master = 20000 + j2.start_us + j2.length_us
    assert across.arrival(20000) == 40000 + j1.start_us + j1.length_us + e
    assert at_master < 40000 + j1.start_us
    dds = Carriage("y", "lan", "pc", "pc2", None, None, 1500)
    assert dds.arrival(20000) == 21500


def errors(text: str) -> list[tuple[int, int, str, str | None]]:
    result = check_file("/tmp/arm.elab", text=text)
    return [(d.span.line, d.span.column, d.message, d.hint) for d in result.diagnostics.sorted()]


def test_the_robot_with_its_delays_checks():
    result = check_file("/tmp/arm.elab", text=ROBOT)
    assert result.model is not None, result.report()
    plan = result.timing.links
    assert sorted(plan.rounds) == ["bus"] and sorted(plan.carriages) == ["goal1", "goal2", "pos1"]


def test_a_channel_across_the_bus_needs_one_more_token_than_within_a_node():
    # Within one node, delay 1 is enough between two 20 ms tasks; across the bus the value
    # published at 20 ms reaches j1 at 30.7 ms, after c1's release at 20 ms.
    text = variant("channel goal1: int16 delay 2 over bus", "channel goal1: int16 delay 1 over bus")
    assert errors(text) == [(*position(text, "goal1"), "channel 'goal1' runs dry: it crosses link 'bus' from node "
                             "'pc' to node 'j1', where a value reaches task 'c1' up to 10688 us after task 'plan' "
                             "publishes it; it needs 1 more initial token(s)", "declare it with: delay 2")]


def test_upwards_the_delay_covers_the_slot():
    text = variant("channel pos1: int32 delay 2 over bus", "channel pos1: int32 delay 1 over bus")
    assert errors(text) == [(*position(text, "pos1"), "channel 'pos1' runs dry: it crosses link 'bus' from node "
                             "'j1' to node 'pc', where a value reaches task 'plan' up to 10497 us after task 'c1' "
                             "publishes it; it needs 1 more initial token(s)", "declare it with: delay 2")]


def test_an_offset_consumer_can_take_the_value_in_the_same_period():
    # c2 is released at 5 ms + k 20 ms: the value published at 20 ms arrives at 37.3 ms, before 45 ms
    text = variant("channel goal2: int16 delay 2 over bus", "channel goal2: int16 delay 1 over bus")
    found = errors(text)
    assert len(found) == 1 and "needs 1 more initial token(s)" in found[0][2], found


def test_a_round_too_long_for_its_period():
    text = variant("baud 115200", "baud 9600")
    line, col = position(text, "bus modbus")
    # at 9600 baud a character is 1145.83 us and t3.5 4010.42 us: the sync 8 characters + t3.5 + 1 ms
    # = 14177.08 us, j1's slot 26 characters + 2 t3.5 + 1 ms = 38812.5 us, j2's 22 characters ... = 34229.17 us
    assert errors(text) == [(line, col, "the round of link 'bus' takes 87219 us (sync 14178 us, slot of 'j1' "
                             "38813 us, slot of 'j2' 34230 us) at 9600 baud, longer than its period of 20000 us: "
                             "it cannot carry its channels",
                             "lengthen the round, raise the baud rate or carry fewer values")]


def test_a_slot_with_more_registers_than_function_23_moves():
    text = variant("    r.y -> goal1\n", "    u = Upsample<int16>(factor = 125)\n    r.y -> u.x\n    u.y -> goal1\n")
    text = variant("    goal1 -> g.x\n", "    d = Downsample<int16>(factor = 125)\n    goal1 -> d.x\n    d.y -> g.x\n",
                   text)
    found = errors(text)
    assert [f[2] for f in found] == ["link 'bus' cannot carry its channels: 125 registers written to node 'j1' in "
                                     "one slot, more than function 23's 121 ('goal1' (125))"]


def test_a_dds_channel_waits_for_its_latency():
    text = variant("node j2 board avr mcu atmega328p", "node j2 board avr mcu atmega328p\nnode pc2 board host")
    text = variant("    peer pc\n", "    peer pc\n    peer pc2\n", text)
    text = variant("link lan dds domain 7", "link lan dds domain 7 latency 25 ms", text)
    text = variant("channel goal2: int16 delay 2 over bus", "channel goal2: int16 delay 1 over lan", text)
    text = variant("task c2 on j2", "task c2 on pc2", text)
    text = variant('device m2: Motor(pwm = "PD6", dir = "PD7") on j2',
                   'device m2: Motor(pwm = "PD6", dir = "PD7") on pc2', text)
    text = variant("    slave j2 on uart0 unit 3\n", "", text)
    found = errors(text)
    # published at 20 ms, usable from 45 ms: c2's release at 45 ms takes it; delay 2 covers 5 and 25 ms
    assert [f[2] for f in found] == ["channel 'goal2' runs dry: it crosses link 'lan' from node 'pc' to node "
                                     "'pc2', where a value reaches task 'c2' up to 25000 us after task 'plan' "
                                     "publishes it; it needs 1 more initial token(s)"]


def test_the_values_each_slot_carries_round_by_round():
    from easylab.analysis.distribution import RegisterBlock, carry_counts

    r = two_slaves()
    # a slave's output published every 20 ms at its deadline (20 ms): the first at 20 ms is read in round 1
    up = Carriage("pos", "bus", "j1", "pc", r, "pc")
    assert carry_counts(r, up, "j1", 20000, 20000, 1) == ((0, 1, 1), 2)
    # every 10 ms: two values a round from round 1 on (10 and 20 ms are both before round 1's slot)
    assert carry_counts(r, up, "j1", 10000, 10000, 1) == ((0, 2, 2), 2)
    # published just before the slot, within the sync error: the value waits one round
    late = carry_counts(r, up, "j1", 20000 + r.slots[0].start_us - 1, 20000, 1)
    assert late == ((0, 0, 1, 1), 3)
    # to a slave from the master: written in the first slot of that slave at or after its publication
    down = Carriage("goal", "bus", "pc", "j2", r, "pc")
    assert carry_counts(r, down, "j2", 20000, 20000, 1) == ((0, 1, 1), 2)
    # the master's values every 30 ms over 20 ms rounds: a pattern of three rounds that repeats
    counts, repeat_from = carry_counts(r, down, "j2", 30000, 30000, 1)
    block = RegisterBlock("goal", 0, 2, 2, 1, counts, repeat_from)
    carried = [block.carried(n) for n in range(20)]
    # j2's slot starts 10.5 ms into the round: 30 ms -> round 1, 60 -> 3, 90 -> 4, 120 -> 6, 150 -> 7, ...
    assert carried[:8] == [0, 1, 0, 1, 1, 0, 1, 1]
    assert all(carried[n] == carried[n + 3] for n in range(1, 17))
    assert sum(carried[:11]) == 7  # every value published up to 210 ms, before round 10's slot
