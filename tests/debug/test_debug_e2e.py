"""Every function of the debug protocol end to end: host builds of the
examples, served on a real pty, driven by the project's client."""

from __future__ import annotations

import re
import struct
import time

import pytest

from debug_testlib import EXAMPLES, board, builds, firmware, host_only, on_boards  # noqa: F401 (fixtures)
from easylab.host_tools.debug_protocol import K, DebugError, crc16, cobs_encode, encode_frame
from easylab.host_tools.transport import TransportError

EXAMPLE_NAMES = sorted(p.stem for p in EXAMPLES.glob("*.elab"))

# The firmware of each test runs on the board of its `board` parameter
# (@on_boards: host and the AVR in simavr; @host_only: the AVR skipped, why).
pytestmark = pytest.mark.usefixtures("board")


def ids(fw, *names):
    m = fw.map
    return [(m.item(n).id, m.item(n).type, m.item(n).count) for n in names]


@on_boards
@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_every_example_identifies_itself_and_reads_every_item(builds, firmware, name):
    fw = firmware(builds[name])
    c = fw.client()
    m = fw.map
    assert c.hello_info.program_id == m.program_id == c.program_id()
    assert c.hello_info.version == K.PROTOCOL_VERSION and c.hello_info.max_frame == K.MAX_FRAME
    assert c.hello_info.item_count == len(m.items)
    values = c.read([(i.id, i.type, i.count) for i in m.items])
    assert len(values) == len(m.items)
    for item in m.items:  # the firmware's idea of every item agrees with the map
        info = c.item_info(item.id)
        assert (info["type"], info["kind"], info["count"], info["flags"]) == \
            (item.type, item.kind, item.count, item.flags)
        if item.range:
            assert info["range"] == pytest.approx(item.range)
    f = c.flags()
    assert f.halted and f.why == "start" and f.tick == 0
    s = c.stack()
    assert len(s.charts) == len(m.charts) and s.task is None


@host_only("a debugger write to a device `out` datum (end_out.level) holds on the host board until the next "
           "stimulus read; on a target the driver's next read() of the pin replaces it (docs/protocol.md)")
def test_writes_change_the_behaviour_in_the_trace(builds, firmware):
    # Without a write the cylinder stays retracted ...
    fw = firmware(builds["pneumatic_cylinder"], duration="100ms")
    c = fw.client()
    c.run()
    assert fw.wait_exit()[0] == 0
    assert {r["Cylinder.active"] for r in fw.rows()} <= {"", "Retracted"}
    # ... with start_cmd written at the start it extends, and with the end
    # switch forced (a device `out` datum, no stimulus) it reaches Extended.
    fw = firmware(builds["pneumatic_cylinder"], duration="100ms")
    c = fw.client()
    m = fw.map
    assert c.write(m.item("start_cmd").id, "bool", True) == K.APPLIED  # halted at an instant: at once
    c.bp_set(K.P_STEP, 0, 1)  # Cylinder.Extending
    c.run()
    fw.wait_halted(c)
    assert c.write(m.item("end_out.level").id, "bool", True) == K.QUEUED  # inside an activation: next instant
    assert c.flags().writes_pending == 1
    c.bp_clear()
    c.run()
    assert fw.wait_exit()[0] == 0
    rows = fw.rows()
    states = [r["Cylinder.active"] for r in rows]
    assert "Extending" in states and "Extended" in states
    first_ext = next(r for r in rows if r["Cylinder.active"] == "Extended")
    assert first_ext["end_out.level"] == "1" and first_ext["cycles"] == "1"
    assert rows[0]["time_us"] == "0" and rows[0]["start_cmd"] == "1"


@on_boards
def test_read_only_range_and_type_checks(builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"])
    c = fw.client()
    m = fw.map
    with pytest.raises(DebugError) as e:
        c.write(m.item("valve.duty").id, "int16", 10)
    assert e.value.status == K.E_READ_ONLY
    with pytest.raises(DebugError) as e:
        c.write(m.item("target").id, "int16", 2000)  # range 0..1023
    assert e.value.status == K.E_RANGE
    with pytest.raises(DebugError) as e:  # a bool is 0 or 1
        c.request(K.CMD_WRITE, struct.pack("<HHB", m.item("start_cmd").id, 0, 2))
    assert e.value.status == K.E_VALUE
    with pytest.raises(DebugError) as e:  # the value has the item's size
        c.request(K.CMD_WRITE, struct.pack("<HHI", m.item("target").id, 0, 5))
    assert e.value.status == K.E_LENGTH
    with pytest.raises(DebugError) as e:
        c.read_raw([len(m.items)])
    assert e.value.status == K.E_ID
    with pytest.raises(DebugError) as e:  # 80 ids: the answer cannot fit
        c.read_raw([m.item("timeout").id] * 70)
    assert e.value.status in (K.E_TOO_BIG, K.E_LENGTH)
    assert c.read(ids(fw, "target", "timeout", "start_cmd")) == [900, 2000, False]
    c.write(m.item("timeout").id, "time", 5000)
    c.write(m.item("PositionControl.pid.integral").id, "int32", -123456)
    assert c.read(ids(fw, "timeout", "PositionControl.pid.integral")) == [5000, -123456]


@on_boards
def test_a_model_with_unsigned_ranges_only_still_checks_them(builds, firmware):
    """blink's server is compiled without signed and float range keys
    (el_debug_config.h): its uint16 range is checked at both ends."""
    fw = firmware(builds["blink"])
    c = fw.client()
    half = fw.map.item("half_period")
    for bad in (9, 5001, 65535):
        with pytest.raises(DebugError) as e:
            c.write(half.id, "uint16", bad)
        assert e.value.status == K.E_RANGE
    for good in (10, 5000):
        assert c.write(half.id, "uint16", good) == K.APPLIED
        assert c.read(ids(fw, "half_period")) == [good]


@on_boards
def test_an_element_of_an_item_of_several_is_written_alone(builds, firmware):
    """pt100_sensor's moving-average window (uint16 x 8): a write sets one
    element, a read returns all of them, an element beyond is E_VALUE."""
    fw = firmware(builds["pt100_sensor"])
    c = fw.client()
    window = fw.map.item("Acquire.avg.window")
    before = c.read(ids(fw, "Acquire.avg.window"))[0]
    assert c.write(window.id, "uint16", 4321, elem=5) == K.APPLIED
    assert c.read(ids(fw, "Acquire.avg.window"))[0] == before[:5] + [4321] + before[6:]
    with pytest.raises(DebugError) as e:
        c.write(window.id, "uint16", 1, elem=8)
    assert e.value.status == K.E_VALUE


@on_boards
def test_a_transaction_of_16_writes_is_never_seen_half_applied(builds, firmware):
    fw = firmware(builds["tx16"], halt=False, fast=False)  # real time: commits land between instants
    c = fw.client()
    m = fw.map
    params = [m.item(f"p{i}") for i in range(16)]
    for k in range(1, 21):
        c.tx_begin()
        for p in params:
            c.write(p.id, "int16", k)
        c.read_raw([params[0].id, params[15].id])  # queued reads: values at the instant of the commit
        how, data = c.tx_commit()
        while how != K.APPLIED:
            state, data = c.tx_result()
            how = K.APPLIED if state == 3 else how
        assert struct.unpack("<hh", data) == (k, k)
        values = c.read([(p.id, "int16", 1) for p in params])
        assert values == [k] * 16
    # A full queue is refused clearly; abort leaves nothing behind.
    c.tx_begin()
    for p in params + params[:8]:
        c.write(p.id, "int16", 99)
    with pytest.raises(DebugError) as e:
        c.write(params[0].id, "int16", 99)
    assert e.value.status == K.E_QUEUE_FULL
    with pytest.raises(DebugError) as e:
        c.tx_begin()
    assert e.value.status == K.E_TX_BUSY
    c.tx_abort()
    with pytest.raises(DebugError) as e:
        c.tx_commit()
    assert e.value.status == K.E_NO_TX
    time.sleep(0.05)
    fw.stop()
    rows = fw.rows()
    assert len(rows) >= 20
    for row in rows:
        assert len({row[f"p{i}"] for i in range(16)}) == 1, f"half-applied transaction: {row}"
    assert rows[-1]["p0"] == "20"


@on_boards
def test_breakpoints_halt_at_the_right_item(builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"])
    c = fw.client()
    m = fw.map
    c.write(m.item("start_cmd").id, "bool", True)
    trans = next(t for t in m.charts[0]["transitions"] if t["name"] == "Retracted -> Extending")
    pid = next(a for a in m.actors if a["name"] == "PositionControl.pid")
    slots = {
        "transition": c.bp_set(K.P_TRANSITION, 0, trans["id"]),
        "step": c.bp_set(K.P_STEP, 0, 1),
        "actor": c.bp_set(K.P_ACTOR, pid["id"]),
        "task": c.bp_set(K.P_TASK, 1),  # lamp
    }
    assert len(set(slots.values())) == 4
    assert c.bp_set(K.P_STEP, 0, 1) == slots["step"]  # the same point: the same breakpoint
    with pytest.raises(DebugError) as e:
        c.bp_set(K.P_STEP, 0, 99)
    assert e.value.status == K.E_ID
    seen = []
    for _ in range(4):
        c.run()
        f = fw.wait_halted(c)
        s = c.stack()
        seen.append((f.why, s.location.kind, s.location.a, s.location.b, f.breakpoint, s.task, s.actor, s.charts,
                     f.tick))
    # tick 0: the chart enters Retracted; lamp's first activation follows control's
    assert seen[0][:6] == ("breakpoint", K.P_TASK, 1, 0, slots["task"], 1)
    # tick 1: Retracted -> Extending fires, Extending becomes active, then PositionControl runs
    assert seen[1][:6] == ("breakpoint", K.P_TRANSITION, 0, trans["id"], slots["transition"], 0)
    assert seen[2][:6] == ("breakpoint", K.P_STEP, 0, 1, slots["step"], 0) and seen[2][7] == [[1]]
    assert seen[3][:7] == ("breakpoint", K.P_ACTOR, pid["id"], 0, slots["actor"], 0, pid["id"])
    assert [x[8] for x in seen] == [0, 1, 1, 1]
    hits = {b.slot: b.hits for b in c.bp_list()}
    assert hits[slots["actor"]] == 1 and hits[slots["task"]] == 1
    c.bp_clear(slots["actor"])
    with pytest.raises(DebugError):
        c.bp_clear(slots["actor"])
    assert len(c.bp_list()) == 3
    c.bp_clear()
    assert c.bp_list() == []


@on_boards
def test_step_advances_exactly_one_unit(builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"])
    c = fw.client()
    fw.wait_halted(c)  # --debug ...,halt: the link may come up before the first instant's halt
    m = fw.map
    c.write(m.item("start_cmd").id, "bool", True)

    def step(unit):
        c.step(unit)
        f = fw.wait_halted(c)
        assert f.why == "step"
        return f.tick, f.location.kind, f.location.a, f.location.b

    # tasks: control (every tick) and lamp (every 20 ticks) are both released at tick 0
    assert [step("task") for _ in range(4)] == [
        (0, K.P_TASK, 0, 0), (0, K.P_TASK, 1, 0), (1, K.P_TASK, 0, 0), (2, K.P_TASK, 0, 0)]
    # a chart step ends where the evolution does: the one under way (tick 2), then the next one
    assert [step("chart") for _ in range(2)] == [(2, K.P_CHART_END, 0, 0), (3, K.P_CHART_END, 0, 0)]
    order = [a["id"] for a in m.actors if a["name"].startswith("PositionControl.")]
    fired = [step("actor")[2] for _ in range(6)]
    assert sorted(fired[:3]) == sorted(order) and fired[3:] == fired[:3]  # one firing each, per activation
    assert [step("instant")[:2] for _ in range(3)] == [(6, K.P_INSTANT), (7, K.P_INSTANT), (8, K.P_INSTANT)]
    c.run()
    with pytest.raises(DebugError) as e:
        time.sleep(0.05)
        c.step("task")
    assert e.value.status == K.E_NOT_HALTED


@on_boards
@pytest.mark.realtime  # counts ticks against the wall clock: a starved simulator falls behind it
def test_break_run_and_resync_in_real_time(builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"], halt=False, fast=False)  # tick 5 ms, real time
    c = fw.client()
    time.sleep(0.2)
    c.halt()
    f = fw.wait_halted(c)
    assert f.why == "break" and f.location.kind == K.P_INSTANT
    tick = f.tick
    time.sleep(0.5)  # halted: logical time stands still
    assert c.flags().tick == tick
    c.run()
    t0 = time.monotonic()
    time.sleep(0.3)
    after = c.flags().tick
    elapsed = time.monotonic() - t0
    # real time resumed from the halted tick, without catching up the 0.5 s
    assert 0.5 * elapsed / 0.005 <= after - tick <= elapsed / 0.005 + 10
    status, _, err = fw.stop()
    assert status == 0
    # Catching up the halted 0.5 s would overrun about 100 activations; a
    # loaded machine may make a few late, which the firmware reports.
    overruns = sum(int(n) for line in err.splitlines() if "overruns:" in line
                   for n in re.findall(r" (\d+)\b", line.split("overruns:", 1)[1]))
    assert overruns < 20, err
    rows = fw.rows()
    times = [int(r["time_us"]) for r in rows]
    assert times == sorted(times) and len(set(times)) == len(times)


@host_only("the host board's RESET re-executes the process, which starts a new trace file and removes its link "
           "at exit; the AVR's watchdog reset restarts the MCU inside the same harness, whose one trace file holds "
           "the rows of both runs")
def test_reset_restarts_the_program(builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"])
    c = fw.client()
    m = fw.map
    c.write(m.item("kp").id, "int16", 1234)
    c.write(m.item("start_cmd").id, "bool", True)
    for _ in range(31):
        c.step("instant")
        fw.wait_halted(c)
    assert c.flags().tick == 31
    assert c.stack().charts == [[1]]
    c.reset(halt=True)
    assert c.hello_again().program_id == m.program_id
    f = fw.wait_halted(c)  # the restarted program may answer before its first instant
    assert f.halted and f.why == "start" and f.tick == 0
    assert c.read(ids(fw, "kp", "start_cmd")) == [400, False]
    assert c.stack().charts == [[None]]
    assert fw.link.exists()
    c.run()
    time.sleep(0.2)
    fw.stop()
    assert not fw.link.exists()  # the restarted process removes the link at exit
    assert fw.rows()[0]["time_us"] == "0" and fw.rows()[0]["kp"] == "400"


@on_boards
def test_damaged_frames_are_counted_and_the_next_good_frame_works(builds, firmware):
    fw = firmware(builds["blink"])
    c = fw.client()
    port = c.t.port
    before = c.counters()
    good = encode_frame(7, K.CMD_GET_PROGRAM_ID)
    bad_crc = bytearray(good)
    bad_crc[2] ^= 0x55
    body = bytes([8, K.CMD_HELLO])
    oversize = cobs_encode(bytes(range(1, 200)) * 2) + b"\x00"
    truncated = cobs_encode(b"\x09") + b"\x00"
    cut = b"\x05ab\x00"  # a block that promises 4 bytes and ends after 2
    unknown_body = bytes([10, 0x7E])
    crc = crc16(unknown_body)
    unknown = cobs_encode(unknown_body + bytes([crc & 0xFF, crc >> 8])) + b"\x00"
    for junk in (bytes(bad_crc), oversize, truncated, cut, b"\x00\x00"):
        port.write(junk)
    port.write(unknown)

    # the unknown command is answered; the good frame after all that works
    with pytest.raises(DebugError) as e:
        c.request(0x7D)
    assert e.value.status == K.E_UNKNOWN_CMD
    assert c.program_id() == fw.map.program_id
    after = c.counters()
    assert after["bad_crc"] == before["bad_crc"] + 1
    assert after["oversize"] == before["oversize"] + 1
    assert after["truncated"] == before["truncated"] + 2
    assert after["unknown"] == before["unknown"] + 2
    # a repeated request (same seq, same CRC: its answer was lost) is answered
    # from the cache, not run twice
    m = fw.map
    c.bp_set(K.P_TASK, 0)
    c.run()
    fw.wait_halted(c)  # halted at a task: writes queue for the next instant
    frame = encode_frame(c.seq + 1, K.CMD_WRITE, struct.pack("<HHH", m.item("half_period").id, 0, 100))
    port.write(frame)
    port.write(frame)
    time.sleep(0.2)
    c.t.discard_input()
    c.seq += 1
    assert c.flags().writes_pending == 1
    assert c.counters()["duplicates"] == after["duplicates"] + 1


@on_boards
def test_tcp_transport(builds, firmware, tmp_path):
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    fw = firmware(builds["blink"], transport=f"tcp:{port}")
    from easylab.host_tools.debug_protocol import DebugClient
    deadline = time.monotonic() + 5
    while True:
        try:
            c = DebugClient.open(f"socket://127.0.0.1:{port}", 2.0)
            break
        except Exception:
            assert time.monotonic() < deadline
            time.sleep(0.05)
    fw.clients.append(c)
    assert c.hello().program_id == fw.map.program_id
    assert c.read(ids(fw, "half_period")) == [500]
    c.close()
    c2 = DebugClient.open(f"socket://127.0.0.1:{port}", 2.0)  # a second client after the first left
    fw.clients.append(c2)
    assert c2.hello().program_id == fw.map.program_id


# Round trips a flood makes in a second at the least: every one carries
# all of cd_to_dat's items over a 115200-baud wire; on the PIC18 (10 MIPS)
# its debug server's work adds to that, and gpsim keeps real time only
# while it has a core to itself.
FLOOD_ROUND_TRIPS = {"pic18": 15}


@on_boards
def test_dispatcher_keeps_time_while_a_client_floods_it(builds, firmware, board):
    """Serving the debugger never makes the dispatcher late (bounded work)."""
    fw = firmware(builds["cd_to_dat"], halt=False, fast=False)
    c = fw.client()
    m = fw.map
    allitems = [(i.id, i.type, i.count) for i in m.items]
    t0 = time.monotonic()
    n = 0
    try:
        while time.monotonic() - t0 < 1.0:
            c.read(allitems)
            c.flags()
            n += 1
    except TransportError as lost:  # the firmware (or its simulator) said why on stderr
        status, _, err = fw.stop()
        raise AssertionError(f"{lost} after {n} round trips; status {status}, stderr:\n{err}") from None
    status, _, err = fw.stop()
    assert n > FLOOD_ROUND_TRIPS.get(board, 50) and status == 0 and "overruns" not in err, (n, err)

