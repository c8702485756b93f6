"""Forcing and conditional breakpoints (docs/protocol.md, "Forcing and
conditional breakpoints"): a forced sensor holds across instants on the
host board (the device trace shows it) and its release restores the
stimulus; a conditional breakpoint halts at the right instant on the host
board, in local execution and on the AVR in simavr, and, over random
comparisons and values, at the first instant where the condition evaluated
in Python on the un-halted trace turns true; the setting's checks and
what a model without slots answers."""

from __future__ import annotations

import csv
import functools
import operator
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from debug_testlib import (EXAMPLES, ROOT, Firmware, board, build, builds, env_with_tools,  # noqa: F401
                           firmware)

from easylab.host_tools.debug_protocol import K, DebugError

ENV = env_with_tools()
MODEL = "examples/pneumatic_cylinder.elab"
STIMULUS = EXAMPLES / "pneumatic_cylinder.stimulus.csv"
TICK_US = 5000  # the model's tick: its control task's period


def console(fw, commands: str, timeout=120):
    proc = subprocess.run([sys.executable, "-m", "easylab.host_tools.debug_console", "--map", str(fw.map_path),
                           str(fw.link), "-c", commands], capture_output=True, text=True, timeout=timeout,
                          env=ENV)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout.splitlines()


def trace_rows(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def value_at(rows: list[dict], column: str, time_us: int) -> str:
    """A column's value at an instant: the CSV trace has a row only where
    something changed, so the last row at or before it."""
    value = None
    for r in rows:
        if int(r["time_us"]) > time_us:
            break
        value = r[column]
    return value


def stimulus_at(column: str, time_us: int) -> str:
    """The stimulus's value of a column at a time (its last non-empty cell)."""
    value = None
    for r in trace_rows(STIMULUS):
        if int(r["time_us"]) > time_us:
            break
        if r[column] != "":
            value = r[column]
    return value


@pytest.mark.parametrize("board", ["host", "interp", "avr", "pic18"], indirect=True)
def test_force_holds_end_out_across_instants_and_release_restores_the_stimulus(board, builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"], "--stimulus", str(STIMULUS), duration="600ms")
    lines = console(fw, "force end_out.level 1; forced; info; break when cycles >= 1; run; wait; "
                        "release end_out.level; forced; delete all; run")
    assert lines[0] == "end_out.level forced to true (from now, every instant until released)"
    assert lines[1] == "end_out.level = true (forced)"
    assert any("forced: end_out.level" in line for line in lines), lines  # info names them
    assert "breakpoint 8 when cycles >= 1" in lines
    # forced from the start, the cylinder is out as soon as it starts to extend (20 ms): Extended at 25 ms,
    # `cycles` counted there, seen at the next instant
    at = fw.map.item("cycles").location  # the PIC18's variant of the model has other lines
    assert board == "pic18" or at == f"{MODEL}:19"
    assert f"halted (breakpoint) at breakpoint 8 when cycles >= 1 ({at}), 30 ms (tick 6)" in lines
    assert "released end_out.level" in lines and "nothing forced" in lines
    status, _, err = fw.wait_exit(timeout=60)
    assert status == 0, err
    rows = trace_rows(fw.trace)
    # held at every instant up to the release although the stimulus says 0 (its device is read every 5 ms)
    assert all(value_at(rows, "end_out.level", t) == "1" for t in range(0, 30001, TICK_US))
    assert stimulus_at("end_out.level", 30000) == "0"
    # released at 30 ms: the stimulus again from the next read of the device on
    for t in range(35000, 600000, TICK_US):
        assert value_at(rows, "end_out.level", t) == stimulus_at("end_out.level", t), t


def test_force_over_the_protocol_is_in_the_status_and_checked(builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"])
    c = fw.client()
    m = fw.map
    end_out, target, valve = m.item("end_out.level"), m.item("target"), m.item("valve.duty")
    assert (c.hello_info.force_slots, c.hello_info.cond_slots) == (K.FORCE_MAX, K.COND_MAX)
    assert not c.flags().status & K.S_FORCED
    assert c.force(end_out.id, "bool", 1) == K.APPLIED  # halted at an instant: at once
    assert c.read([(end_out.id, "bool", 1)]) == [1]
    assert c.flags().status & K.S_FORCED
    with pytest.raises(DebugError) as e:
        c.force(valve.id, "int16", 5)  # a device `in` datum: the application's output
    assert e.value.status == K.E_READ_ONLY
    kp = m.item("kp")
    assert c.force(target.id, "int16", 100) == K.APPLIED and c.force(kp.id, kp.type, 7) == K.APPLIED
    assert c.force(kp.id, kp.type, 8) == K.APPLIED  # forced again: a new value, the same slot
    with pytest.raises(DebugError) as e:
        c.force(kp.id, kp.type, 5000)  # outside kp's range 0..4000
    assert e.value.status == K.E_RANGE
    forced = {(f.item, f.elem): f.value for f in c.forced()}
    assert forced == {(end_out.id, 0): b"\x01", (target.id, 0): (100).to_bytes(2, "little"),
                      (kp.id, 0): (8).to_bytes(2, "little")}
    c.run()  # held while it runs: the chart's entry actions and the stimulus-less devices leave them
    c.halt()
    fw.wait_halted(c)
    assert c.read([(kp.id, kp.type, 1), (target.id, "int16", 1), (end_out.id, "bool", 1)]) == [8, 100, 1]
    c.release(end_out.id)
    with pytest.raises(DebugError) as e:
        c.release(end_out.id)
    assert e.value.status == K.E_ID
    c.release()
    assert c.forced() == [] and not c.flags().status & K.S_FORCED


@pytest.mark.parametrize("board", ["host", "interp", "avr", "pic18"], indirect=True)
def test_conditional_breakpoint_halts_at_the_instant_it_turns_true(board, builds, firmware):
    """position.value reaches 700 at 120 ms in the stimulus: the halt is
    there, named with the item's file:line and the time in ms; it halts
    again only once the condition was false (the edge), and clears like
    the other breakpoints."""
    fw = firmware(builds["pneumatic_cylinder"], "--stimulus", str(STIMULUS), duration="1500ms")
    lines = console(fw, "break when position.value >= 700; break when Cylinder == Extended; breakpoints; run; "
                        "wait; run; wait; run; wait; breakpoints; delete 8; breakpoints; delete all; run")
    # the model's lines (the PIC18 runs a variant of it with its debug UART moved: other lines)
    at, chart_at = f"({fw.map.item('position.value').location})", f"({fw.map.charts[0]['location']})"
    if board != "pic18":
        assert (at, chart_at) == (f"({MODEL}:7)", f"({MODEL}:39)")
    slots = [line for line in lines if line.startswith("breakpoint ")]
    assert slots == ["breakpoint 8 when position.value >= 700", "breakpoint 9 when Cylinder.active == Extended"]
    halts = [line for line in lines if line.startswith("halted")]
    assert halts == [
        f"halted (breakpoint) at breakpoint 8 when position.value >= 700 {at}, 120 ms (tick 24)",
        # the chart enters Extended at 160 ms (end_out), seen at the next instant
        f"halted (breakpoint) at breakpoint 9 when Cylinder.active == Extended {chart_at}, 165 ms (tick 33)",
        # position falls below 700 at 320 ms, is back at 800 at 1300 ms: the next edge
        f"halted (breakpoint) at breakpoint 8 when position.value >= 700 {at}, 1300 ms (tick 260)",
    ], lines
    listed = [line for line in lines if line.startswith(("8: ", "9: "))]
    assert listed[:2] == [f"8: position.value >= 700 {at} (hit 0 times)",
                          f"9: Cylinder.active == Extended {chart_at} (hit 0 times)"]
    assert f"8: position.value >= 700 {at} (hit 2 times)" in listed[2:4]
    assert listed[-1].startswith("9: ")


# ---- property: the halting instant over random comparisons and values ----

ITEMS = {  # item -> (its trace column, the least value of its type drawn)
    "position.value": ("position.value", -5),
    "end_out.level": ("end_out.level", 0),
    "end_in.level": ("end_in.level", 0),
    "cycles": ("cycles", 0),  # uint32
    "valve.duty": ("valve.duty", -5),
    "target": ("target", -5),
}
PY_OPS = {"==": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le, ">": operator.gt,
          ">=": operator.ge}
DURATION_US = 1_500_000


@functools.lru_cache(maxsize=None)
def _unhalted_trace(exe: Path, out: Path) -> tuple:
    """The trace of the run with no breakpoint (rows, as tuples of items)."""
    trace = out / "unhalted.trace.csv"
    subprocess.run([str(exe), "--stimulus", str(STIMULUS), "--trace", str(trace), "--fast", "--duration",
                    f"{DURATION_US // 1000}ms"], check=True, timeout=60, stdin=subprocess.DEVNULL)
    return tuple(tuple(r.items()) for r in trace_rows(trace))


def _first_true_tick(rows: list[dict], column: str, op: str, value: int) -> int | None:
    for t in range(0, DURATION_US, TICK_US):
        if PY_OPS[op](int(value_at(rows, column, t)), value):
            return t // TICK_US
    return None


def _values_seen(rows) -> dict:
    return {name: sorted({int(dict(r)[col]) for r in rows}) for name, (col, _) in ITEMS.items()}


def draw_condition(data, exe, tmp_path_factory) -> tuple[str, str, int, int | None]:
    """A random condition on pneumatic_cylinder's items (a value it takes or
    one near its range) and the tick at which it first turns true on the
    un-halted trace of ``exe`` (None: never)."""
    rows = [dict(r) for r in _unhalted_trace(exe, tmp_path_factory.mktemp("unhalted"))]
    name = data.draw(st.sampled_from(sorted(ITEMS)), label="item")
    op = data.draw(st.sampled_from(sorted(PY_OPS)), label="op")
    seen = _values_seen(rows)[name]
    lo, hi = (0, 1) if name.endswith(".level") else (ITEMS[name][1], max(seen) + 5)
    value = data.draw(st.one_of(st.sampled_from(seen), st.integers(lo, hi)), label="value")
    return name, op, value, _first_true_tick(rows, ITEMS[name][0], op, value)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture],
          derandomize=True)
@given(data=st.data())
def test_halting_instant_is_where_the_condition_first_turns_true(builds, tmp_path_factory, data):
    exe = builds["pneumatic_cylinder"]
    name, op, value, expected = draw_condition(data, exe, tmp_path_factory)
    # one process per example, in a folder of its own (the fixture's folder is the test's, shared by examples)
    fw = Firmware(exe, tmp_path_factory.mktemp("run"), "--stimulus", str(STIMULUS),
                  duration=f"{DURATION_US // 1000}ms")
    try:
        c = fw.client()
        it = fw.map.item(name)
        c.bp_when(it.id, it.type, op, value)
        c.run()
        if expected is None:
            status, _, err = fw.wait_exit(timeout=60)
            assert status == 0, err
            return
        f = fw.wait_halted(c, timeout=30)
        assert (f.why, f.location.kind, f.location.a, f.tick) == ("breakpoint", K.P_CONDITION, it.id, expected), \
            (name, op, value)
    finally:
        fw.stop()


# ---- the setting, and a server without slots ----

def test_debug_settings_are_checked_with_their_place(tmp_path):
    from easylab.pipeline import lower_file

    text = (ROOT / "examples/blink.elab").read_text().replace("debug on uart0 baud 115200",
                                                             "debug on uart0 baud 115200 force 9 conditions 2")
    model = tmp_path / "bad.elab"
    model.write_text(text)
    program, result = lower_file(model)
    assert program is None
    line = next(n for n, s in enumerate(text.splitlines(), 1) if s.startswith("debug"))
    col = text.splitlines()[line - 1].index("9") + 1
    assert f"{model}:{line}:{col}: error: 'force' takes 0..{K.FORCE_MAX} slots, not 9" in result.report()


def test_a_model_that_asks_gets_its_slots_and_the_328p_none_without(tmp_path):
    from easylab.codegen.debug import debug_slots
    from easylab.pipeline import lower_file

    blink = (ROOT / "examples/blink.elab").read_text()
    asking = tmp_path / "asking.elab"
    asking.write_text(blink.replace("debug on uart0 baud 115200", "debug on uart0 baud 115200 force 3 conditions 1"))
    plain, _ = lower_file(ROOT / "examples/blink.elab")
    asked, _ = lower_file(asking)
    assert debug_slots(plain, small=True) == (0, 0)
    assert debug_slots(plain, small=False) == (K.FORCE_MAX, K.COND_MAX)
    assert debug_slots(asked, small=True) == debug_slots(asked, small=False) == (3, 1)


def test_the_console_completes_the_new_commands(builds):
    from types import SimpleNamespace

    from easylab.host_tools.debug_console import Console
    from easylab.host_tools.debug_map import DebugMap

    dmap = DebugMap.load(builds["pneumatic_cylinder"].parent / "debug_map.json")
    session = SimpleNamespace(url="test", map=dmap, c=SimpleNamespace(hello_info=SimpleNamespace(program_id=0)))
    con = Console(session)
    assert con.completedefault("end_o", "force end_o", 6, 11) == ["end_out.level "]
    assert con.completedefault("valve", "force valve", 6, 11) == []  # a device `in` datum cannot be forced
    assert "all " in con.completedefault("", "release ", 8, 8)
    assert con.completedefault("w", "break w", 6, 7) == ["when "]
    assert con.completedefault("cyc", "break when cyc", 11, 14) == ["cycles "]
    assert con.completedefault(">", "break when cycles >", 18, 19) == ["> ", ">= "]


def test_an_older_firmware_is_refused_with_what_it_lacks():
    import struct

    from easylab.host_tools.debug_protocol import HELLO_FORMAT, DebugClient, ProtocolError

    client = DebugClient.__new__(DebugClient)
    client.t = SimpleNamespaceTransport()
    client.request = lambda cmd, payload=b"", what="", check=True: struct.pack(
        HELLO_FORMAT, K.PROTOCOL_VERSION - 1, 160, 1, 0, 1, 0, 0, 1, 24, 8, 8, 4)
    with pytest.raises(ProtocolError, match="the firmware is older \\(no force, no conditional breakpoints\\); "
                                            "rebuild it with this easylab"):
        client.hello()


class SimpleNamespaceTransport:
    url = "/dev/ttyTEST"

    def discard_input(self):
        pass


def test_a_firmware_without_slots_is_told_apart_by_the_console(builds):
    """HELLO without the slots (a server built with neither): the console
    says how to get them instead of sending requests the server lacks."""
    from types import SimpleNamespace

    from easylab.host_tools.debug_console import CommandError, Session
    from easylab.host_tools.debug_map import DebugMap

    dmap = DebugMap.load(builds["pneumatic_cylinder"].parent / "debug_map.json")
    hello = SimpleNamespace(force_slots=0, cond_slots=0, program_id=0)
    session = Session(SimpleNamespace(hello_info=hello), dmap, "test")
    with pytest.raises(CommandError, match=r"no forcing: declare slots in the model \(`debug on ... force N`"):
        session.execute("force end_out.level 1")
    with pytest.raises(CommandError, match="no conditional breakpoints: .*`debug on ... conditions N`"):
        session.execute("break when cycles >= 1")
