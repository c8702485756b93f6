"""Charts' state as debug items (docs/protocol.md, "Items"): `Chart.active`
and `Chart.Step.time` read and watched in the console on the host board,
in local execution and on the AVR in simavr; `step chart` halting at the
end of the evolution with the step it entered; every halt with the
element's file:line and the logical time in milliseconds; and, over random
charts, the active steps read through the debug interface equal to the
trace's `Chart.active` columns."""

from __future__ import annotations

import json
import random
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from debug_testlib import ROOT, board, build, builds, env_with_tools, firmware, transition_halts  # noqa: F401 (fixtures)

from easylab.host_tools.debug_protocol import K

ENV = env_with_tools()
MODEL = "examples/pneumatic_cylinder.elab"
CHART_AT = f"{MODEL}:39"  # chart Cylinder
EXTENDING_AT = f"{MODEL}:44"


def console(fw, commands: str, *extra, timeout=60):
    proc = subprocess.run([sys.executable, "-m", "easylab.host_tools.debug_console", "--map", str(fw.map_path),
                           str(fw.link), *extra, "-c", commands], capture_output=True, text=True, timeout=timeout,
                          env=ENV)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    return proc.stdout.splitlines()


@pytest.mark.parametrize("board", ["host", "interp", "avr"], indirect=True)
def test_chart_items_read_and_step_chart_shows_the_entered_step(board, builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"])  # halted at its first instant
    lines = console(fw, "read Cylinder Cylinder.active Cylinder.Retracted.time Cylinder.fired; write start_cmd 1; "
                        "step chart; step chart; step chart; step chart; "
                        "read Cylinder Cylinder.Extending.time Cylinder.Retracted.time Cylinder.fired; "
                        "vars Cylinder.*")
    assert lines[:4] == ["Cylinder.active = (none)", "Cylinder.active = (none)", "Cylinder.Retracted.time = 0",
                         "Cylinder.fired = (none)"]
    steps = [line for line in lines if line.startswith("halted (step)")]
    # the first evolution enters the initial step; start_cmd then takes the chart to Extending
    assert steps == [
        f"halted (step) at the end of chart:Cylinder's evolution ({CHART_AT}), 0 ms (tick 0): Cylinder in Retracted",
        f"halted (step) at the end of chart:Cylinder's evolution ({CHART_AT}), 5 ms (tick 1): Cylinder in Extending",
        f"halted (step) at the end of chart:Cylinder's evolution ({CHART_AT}), 10 ms (tick 2): Cylinder in Extending",
        f"halted (step) at the end of chart:Cylinder's evolution ({CHART_AT}), 15 ms (tick 3): Cylinder in Extending",
    ]
    # Step.time: 0 when entered (tick 1), one period (5 ms) more at each evolution; Retracted keeps its last
    # Cylinder.fired: the transition taken at tick 1, kept through the evolutions that fire none
    assert lines[-11:-7] == ["Cylinder.active = Extending", "Cylinder.Extending.time = 10",
                             "Cylinder.Retracted.time = 5", "Cylinder.fired = Retracted -> Extending"]
    listed = lines[-7:]
    assert listed[0].split()[:4] == ["Cylinder.active", "uint8", "chart", "ro"] and listed[0].endswith(CHART_AT)
    assert listed[2].split()[:4] == ["Cylinder.Extending.time", "time", "step_time", "ro"]
    assert listed[2].endswith(EXTENDING_AT) and 'unit "ms"' in listed[2]
    assert listed[6].split()[:4] == ["Cylinder.fired", "uint8", "fired", "ro"] and listed[6].endswith(CHART_AT)


@pytest.mark.parametrize("board", ["host", "interp", "avr"], indirect=True)
def test_chart_items_watched_while_the_program_runs(board, builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"], halt=False, fast=False)  # real time: 5 ms a tick
    lines = console(fw, "write start_cmd 1; sleep 100ms; watch Cylinder Cylinder.Extending.time --every 100ms "
                        "--count 4", "--json")
    rows = [json.loads(line) for line in lines if '"values"' in line]
    assert len(rows) == 4
    assert all(r["values"]["Cylinder.active"] == "Extending" for r in rows), rows  # no end switch: 2 s to the Fault
    times = [r["values"]["Cylinder.Extending.time"] for r in rows]
    ticks = [r["tick"] for r in rows]
    assert times == sorted(times) and times[-1] > times[0], rows
    assert all(t % 5 == 0 for t in times), rows  # grows by the task's period
    assert all(b > a for a, b in zip(ticks, ticks[1:])), rows


@pytest.mark.parametrize("board", ["host", "interp"], indirect=True)
def test_every_halt_names_the_element_its_line_and_the_time_in_ms(board, builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"])
    lines = console(fw, "info; write start_cmd 1; break at Cylinder.Extending; run; wait 5s; stack; "
                        "step task; step actor; delete all; break at Cylinder:Extending->Fault; run; wait 10s")
    assert lines[3] == (f"state       halted (start) at instant (releases task control at {MODEL}:71, "
                        f"task lamp at {MODEL}:72), 0 ms (tick 0)")
    halts = [line for line in lines if line.startswith("halted")]
    assert halts[0] == f"halted (breakpoint) at breakpoint 0 at step Cylinder.Extending ({EXTENDING_AT}), 5 ms (tick 1)"
    assert f"5 ms (tick 1): halted (breakpoint) at breakpoint 0 at step Cylinder.Extending ({EXTENDING_AT})" in lines
    assert halts[1] == f"halted (step) at task:control ({MODEL}:71), 10 ms (tick 2)"
    assert re.fullmatch(rf"halted \(step\) at actor:PositionControl\.\w+ \({MODEL}:2[4-6]\), 10 ms \(tick 2\)",
                        halts[2]), halts[2]
    # the timeout (2 s) from Extending's entry at 5 ms: the guard `Extending.time > timeout` holds at 2010 ms
    assert halts[3] == (f"halted (breakpoint) at breakpoint 0 at Cylinder:Extending->Fault ({MODEL}:60), "
                        f"2010 ms (tick 402)")


@pytest.mark.parametrize("board", ["host", "interp", "avr"], indirect=True)
def test_fired_is_the_transition_just_taken_at_every_transition_breakpoint(board, builds, firmware):
    """pneumatic_cylinder on its stimulus with a breakpoint on every
    transition: at each halt `Cylinder.fired` is the transition halted at
    (none before the first), and it keeps it until the next firing; after a
    reset it is none again (host board: the process starts anew)."""
    fw = firmware(builds["pneumatic_cylinder"], "--stimulus", str(ROOT / "examples" / "pneumatic_cylinder.stimulus.csv"))
    c = fw.client()
    m = fw.map
    fired = m.item("Cylinder.fired")
    read_fired = lambda: c.read([(fired.id, fired.type, 1)])[0]  # noqa: E731
    assert (fired.kind, fired.type, fired.labels[K.NONE8]) == ("fired", "uint8", None)
    assert read_fired() == K.NONE8
    taken = []
    for f in transition_halts(c, m.charts[0]["transitions"]):  # the stimulus's cycles: every transition but one
        assert read_fired() == f.location.b, (f.tick, f.location)
        taken.append(fired.labels[f.location.b])
        c.step("instant")  # on to the next instant, where no transition of a 5 ms chart fires again at once
        fw.wait_halted(c)
        assert read_fired() == f.location.b
    assert taken[:4] == ["Retracted -> Extending", "Extending -> Extended", "Extended -> Retracting",
                         "Retracting -> Retracted"], taken
    assert len(set(taken)) >= 5, taken  # and a timeout's
    if board == "host":
        c.halt()
        fw.wait_halted(c)
        c.reset(halt=True)
        c.hello_again()
        fw.wait_halted(c)
        assert read_fired() == K.NONE8


def test_break_when_a_chart_has_fired_a_transition_named_as_the_console_prints_it(builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"], "--stimulus", str(ROOT / "examples" / "pneumatic_cylinder.stimulus.csv"))
    lines = console(fw, "break when Cylinder.fired == Extending->Extended; run; wait 5s; read Cylinder.fired Cylinder")
    assert lines[0] == "breakpoint 8 when Cylinder.fired == Extending -> Extended"
    assert lines[2].startswith("halted (breakpoint) at breakpoint 8 when Cylinder.fired == Extending -> Extended "
                               f"({CHART_AT}), ")
    assert lines[3:] == ["Cylinder.fired = Extending -> Extended", "Cylinder.active = Extended"]
    proc = subprocess.run([sys.executable, "-m", "easylab.host_tools.debug_console", "--map", str(fw.map_path),
                           str(fw.link), "-c", "break when Cylinder.fired == Extended"], capture_output=True,
                          text=True, env=ENV, timeout=30)
    assert proc.returncode == 1 and "Cylinder.fired: no transition 'Extended' (its transitions: Extended->Retracting" \
        in proc.stderr


def test_a_halt_in_json_has_the_location_and_the_time(builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"])
    lines = console(fw, "write start_cmd 1; step chart; step chart", "--json")
    halt = json.loads(lines[-1])
    assert halt == {"halted": True, "why": "step", "at": f"the end of chart:Cylinder's evolution ({CHART_AT})",
                    "tick": 1, "ms": 5.0, "location": CHART_AT, "active": ["Extending"]}


def test_chart_items_are_read_only(builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"])
    for name in ("Cylinder", "Cylinder.Fault.time", "Cylinder.fired"):
        proc = subprocess.run([sys.executable, "-m", "easylab.host_tools.debug_console", "--map", str(fw.map_path),
                               str(fw.link), "-c", f"write {name} 1"], capture_output=True, text=True, env=ENV,
                              timeout=30)
        assert proc.returncode == 1 and "read-only (a chart's state: only its evolutions change it)" in proc.stderr
    c = fw.client()
    with pytest.raises(Exception) as e:  # the firmware refuses it too
        c.write(fw.map.item("Cylinder.Fault.time").id, "time", 1)
    assert getattr(e.value, "status", None) == K.E_READ_ONLY


def test_the_map_has_the_charts_state_last_and_read_only():
    from easylab.board.registry import load_board
    from easylab.codegen import render as cgen
    from easylab.codegen.debug import buffer_sizes, debug_items
    from easylab.core.paths import templates_dir
    from easylab.host_tools.map_schema import DEBUG_MAP_SCHEMA
    from easylab.pipeline import lower_file
    import jsonschema

    program, _ = lower_file(ROOT / MODEL)
    files = cgen.render(program, load_board("host"), templates_dir())
    m = json.loads(files["debug_map.json"])
    jsonschema.validate(m, DEBUG_MAP_SCHEMA)
    chart_state = [i for i in m["items"] if i["kind"] in ("chart", "step_time", "fired")]
    assert m["items"][-len(chart_state):] == chart_state  # after every other item: their ids are unchanged
    assert [(i["name"], i["type"], i["count"], i["flags"], i.get("step")) for i in chart_state] == [
        ("Cylinder.active", "uint8", 1, ["read"], None),
        *((f"Cylinder.{s}.time", "time", 1, ["read"], k)
          for k, s in enumerate(["Retracted", "Extending", "Extended", "Retracting", "Fault"])),
        ("Cylinder.fired", "uint8", 1, ["read"], None)]
    assert all(i["chart"] == 0 for i in chart_state) and chart_state[2]["location"].endswith(EXTENDING_AT)
    assert "EL_DEBUG_PROBE(EL_DBG_P_CHART_END, 0u, 0u);" in files["model.c"]
    # the charts' state does not grow the server's queues
    from easylab.codegen.c_model import build_view
    items = debug_items(program, build_view(program, load_board("host"), probes=True))
    sizes = buffer_sizes(program, items, len(program.instances))
    without = buffer_sizes(program, [d for d in items if d.kind not in ("chart", "step_time", "fired")],
                           len(program.instances))
    assert (sizes.tx, sizes.writes) == (without.tx, without.writes)


@pytest.mark.parametrize("example", ["pneumatic_cylinder", "line_follower"])
def test_the_fired_transition_is_kept_by_debug_builds_only(example, tmp_path):
    """A debug build sets its chart's `fired` at every transition's firing,
    before the probe; a release build, and a build of the model without a
    debug interface, have no trace of it (their C is what it was before
    the item existed), on every board."""
    from easylab.board.registry import load_board
    from easylab.codegen import render as cgen
    from easylab.core.paths import templates_dir
    from easylab.pipeline import lower_file

    source = ROOT / "examples" / f"{example}.elab"
    nodebug = tmp_path / f"{example}.elab"
    nodebug.write_text(re.sub(r"(?m)^debug on .*$", "", source.read_text()))
    program, _ = lower_file(source)
    plain, _ = lower_file(nodebug)
    for board in ("host", "avr", "pic18", "f16"):
        debug = cgen.render(program, load_board(board), templates_dir())["model.c"]
        for c in program.charts:
            assert debug.count(f"el_c{c.id}_fired = ") == len(c.transitions) + 1  # its definition and each firing
            for t in c.transitions:
                assert (f"el_c{c.id}_fired = {t.id}u;\n"
                        f"                EL_DEBUG_PROBE(EL_DBG_P_TRANSITION, {c.id}u, {t.id}u);") in debug
        for files in (cgen.render(program, load_board(board), templates_dir(), release=True),
                      cgen.render(plain, load_board(board), templates_dir())):
            assert not [name for name, text in files.items() if re.search(r"el_c\d+_fired", text)], board


def test_fired_tells_the_last_of_255_transitions_from_none(firmware, tmp_path):
    """A chart of 255 transitions (the most whose ids leave NONE8 free: its
    item stays uint8): none before the first firing, then transition 254."""
    transitions = [f"    transition {'A -> B' if k % 2 == 0 else 'B -> A'} when {'go' if k == 254 else 'not go'}"
                   for k in range(255)]
    source = tmp_path / "wide.elab"
    source.write_text("\n".join(["model wide", "param go: bool = false", "chart W {", "    initial step A { }",
                                 "    step B { }", *transitions, "}", "task t period 10 ms { run W }",
                                 "debug on uart0 baud 115200", ""]))
    fw = firmware(build(source, tmp_path / "b"))
    lines = console(fw, "read W.fired; step chart; write go true; step chart; read W.fired W")
    assert fw.map.item("W.fired").type == "uint8"
    assert (lines[0], lines[-2:]) == ("W.fired = (none)", ["W.fired = A -> B", "W.active = B"])
    c = fw.client()
    assert c.read([(fw.map.item("W.fired").id, "uint8", 1)]) == [254]


@pytest.mark.parametrize("kind", ["chart", "fired"])
def test_a_map_whose_chart_item_names_no_chart_is_refused(kind, tmp_path):
    from easylab.host_tools.debug_map import DebugMap, MapError

    m = json.loads((Path(build(ROOT / MODEL, tmp_path / "b")).parent / "debug_map.json").read_text())
    del next(i for i in m["items"] if i["kind"] == kind)["chart"]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(m))
    with pytest.raises(MapError, match="chart"):
        DebugMap.load(bad)


# ---------------------------------------------------------------- random charts

FIRED_MODELS = 6  # random firing charts (_firing_chart) whose `fired` items are checked on the host board
FIRED_MODELS_LOCAL = 2  # and in local execution
FIRED_RUN_MS = 600

def _random_chart_models(count: int):
    """The first `count` random models (tests/crosscheck/modelgen.py) with
    charts, from seed 1, with a debug interface."""
    seed = 0
    while count:
        seed += 1
        g = _crosscheck("modelgen").generate(seed, "atmega2560")
        if "\nchart " in g.text:
            count -= 1
            yield g


def _crosscheck(module: str):
    """A module of tests/crosscheck (the random models and their stimuli)."""
    import importlib
    sys.path.insert(0, str(ROOT / "tests" / "crosscheck"))
    try:
        return importlib.import_module(module)
    finally:
        sys.path.pop(0)


def _trace_at(rows: list[dict], time_us: int, column: str) -> set[str]:
    """The trace's value of a column at a time: its last row at or before it
    (a row is written when a value changes)."""
    value = ""
    for row in rows:
        if int(row["time_us"]) > time_us:
            break
        value = row[column]
    return set(value.split("+")) - {""}


@pytest.mark.parametrize("model", list(_random_chart_models(5)), ids=lambda g: g.name)
def test_chart_items_equal_the_traces_active_columns_on_random_charts(model, firmware, tmp_path):
    """At the end of every chart evolution (`step chart`), the chart's
    `active` item is what the trace shows at that activation's deadline
    (the activity is published then), the stack agrees, and each active
    step's time is 0 (entered now) or its previous evolution's plus the
    task's period."""
    source = tmp_path / f"{model.name}.elab"
    source.write_text(model.text + "\ndebug on uart0 baud 115200\n")
    stimulus = tmp_path / f"{model.name}.stimulus.csv"
    stimulus.write_text(_crosscheck("crosscheck").read_columns(source, model.stimulus))
    exe = build(source, tmp_path / "build")
    fw = firmware(exe, "--stimulus", str(stimulus), duration=f"{model.duration_ms}ms")
    m = fw.map
    c = fw.client()
    charts = {ch["id"]: ch for ch in m.charts}
    active_items = {it.chart: it for it in m.items if it.kind == "chart"}
    times = {(it.chart, it.step): it for it in m.items if it.kind == "step_time"}
    deadline_ticks = {t["id"]: t["deadline_us"] // m.tick_us for t in m.tasks}
    period_ms = {t["id"]: t["period_us"] // 1000 for t in m.tasks}
    seen, last_time = [], {}
    # stop stepping while another evolution still comes, and its deadline is traced, before the run ends
    chart_tasks = {ch["task"] for ch in m.charts}
    end_tick = (model.duration_ms * 1000 // m.tick_us - 1
                - max(t["period_us"] // m.tick_us + deadline_ticks[t["id"]] for t in m.tasks if t["id"] in chart_tasks))
    while True:
        c.step("chart")
        f = fw.wait_halted(c)
        if f.tick > end_tick:
            break
        assert f.location.kind == K.P_CHART_END
        chart = charts[f.location.a]
        item = active_items[chart["id"]]
        step_items = [times[chart["id"], s["id"]] for s in chart["steps"]]
        values = c.read([(item.id, item.type, item.count)] + [(t.id, t.type, 1) for t in step_items])
        slots = values[0] if item.count > 1 else [values[0]]
        stack = c.stack().charts[chart["id"]]
        assert [s for s in slots if s != K.NONE8] == [s for s in stack if s is not None], (f.tick, slots, stack)
        names = {m.step_name(chart["id"], s) for s in slots if s != K.NONE8}
        seen.append((f.tick + deadline_ticks[chart["task"]], chart["name"], names))
        for s in (s for s in slots if s != K.NONE8):
            now, before = values[1 + s], last_time.get((chart["id"], s))
            assert now == 0 or (before is not None and now == before + period_ms[chart["task"]]), \
                (chart["name"], s, f.tick, now, before)
        last_time = {k: v for k, v in last_time.items() if k[0] != chart["id"]}
        last_time.update({(chart["id"], s): values[1 + s] for s in slots if s != K.NONE8})
    c.run()
    status, _, err = fw.wait_exit(timeout=60)
    assert status == 0, err
    rows = fw.rows()
    assert len(seen) >= 10
    for tick, name, names in seen:
        assert _trace_at(rows, tick * m.tick_us, f"{name}.active") == names, (name, tick, names)


@dataclass
class FiringChart:
    """A seeded random model whose chart fires often, parallel branches
    together among them (tests/crosscheck's charts mostly wait on values
    that do not change): its text and stimulus."""

    name: str
    text: str
    stimulus: str
    duration_ms: int = 0


def _firing_chart(seed: int) -> FiringChart:
    """A chart of 7 steps (a cycle S0 -> S1 -> S2, and from S0 two parallel
    branches L and R, each looping between two steps, joined into S1) and
    its 8 transitions in random declaration order, with guards on four
    params that a random stimulus toggles and on the steps' times (S0 left
    on time alone)."""
    rng = random.Random(seed)
    params = [f"g{k}" for k in range(4)]

    def guard() -> str:
        roll = rng.random()
        if roll < 0.4:
            return f"{rng.choice(['S0', 'S1', 'S2', 'L0', 'L1', 'R0', 'R1'])}.time >= {rng.choice([0, 5, 10, 20])} ms"
        if roll < 0.7:
            return rng.choice(params)
        if roll < 0.8:
            return f"not {rng.choice(params)}"
        return f"({rng.choice(params)} {rng.choice(['and', 'or'])} {rng.choice(params)})"
    transitions = [f"transition S0 -> (L0, R0) when S0.time >= {rng.choice([0, 5, 10])} ms"]  # it starts
    transitions += [f"transition {src} -> {dst} when {guard()}" for src, dst in [
        ("L0", "L1"), ("L1", "L0"), ("R0", "R1"), ("R1", "R0"), ("(L1, R1)", "S1"),
        ("S1", "S2"), ("S2", "S0")]]
    rng.shuffle(transitions)
    name = f"fired{seed}"
    text = "\n".join([f"model {name}", *(f"param {p}: bool = false" for p in params), "var n: int16",
                      "chart C {", "    initial step S0 { entry n = n + 1 }",
                      *(f"    step {s} {{ }}" for s in ["S1", "S2", "L0", "L1", "R0", "R1"]),
                      *(f"    {t}" for t in transitions), "}", "task t period 5 ms { run C }",
                      "debug on uart0 baud 115200", ""])
    rows, values = ["time_us," + ",".join(params)], [0] * len(params)
    for t_ms in range(0, FIRED_RUN_MS, 5 * rng.randint(1, 4)):
        values = [v if rng.random() < 0.7 else 1 - v for v in values]
        rows.append(f"{t_ms * 1000}," + ",".join(map(str, values)))
    return FiringChart(name, text, "\n".join(rows) + "\n", FIRED_RUN_MS)


@pytest.mark.parametrize("board, model", [
    *(("host", _firing_chart(seed)) for seed in range(1, FIRED_MODELS + 1)),
    *(("interp", _firing_chart(seed)) for seed in range(FIRED_MODELS + 1, FIRED_MODELS + 1 + FIRED_MODELS_LOCAL))],
    ids=lambda x: x if isinstance(x, str) else x.name, indirect=["board"])
def test_fired_is_the_last_transition_of_each_evolution_on_random_charts(board, model, firmware, tmp_path):
    """Over random models with charts (parallel branches among them), on
    the host board and in local execution, run
    by `step chart` with a breakpoint on every transition of the charts the
    breakpoint slots cover: at each transition's halt its chart's `fired`
    item is that transition, which left steps active before the evolution
    and enters steps active after it; at the end of each evolution it is
    the last transition halted at in it (the last in firing order), or the
    one before when none fired; every other covered chart's item keeps its
    value meanwhile."""
    source = tmp_path / f"{model.name}.elab"
    source.write_text(model.text)
    stimulus = tmp_path / f"{model.name}.stimulus.csv"
    stimulus.write_text(model.stimulus)
    exe = source if board == "interp" else build(source, tmp_path / "build")  # local execution runs the model
    duration_ms = model.duration_ms
    fw = firmware(exe, "--stimulus", str(stimulus), duration=f"{duration_ms}ms")
    m = fw.map
    c = fw.client()
    covered, slots = {}, c.hello_info.bp_max
    for ch in m.charts:  # whole charts, while the breakpoint slots last
        if len(ch["transitions"]) <= slots:
            slots -= len(ch["transitions"])
            covered[ch["id"]] = ch
            for tr in ch["transitions"]:
                c.bp_set(K.P_TRANSITION, ch["id"], tr["id"])
    assert covered
    fired_items = {it.chart: it for it in m.items if it.kind == "fired" and it.chart in covered}
    active_items = {it.chart: it for it in m.items if it.kind == "chart"}

    def read(items):
        return c.read([(it.id, it.type, it.count) for it in items])

    def active(chart):
        values = read([active_items[chart]])[0]
        return {s for s in (values if isinstance(values, list) else [values]) if s != K.NONE8}

    expected = {ch: next(k for k, name in fired_items[ch].labels.items() if name is None)  # none yet
                for ch in covered}
    before = {ch: set() for ch in covered}
    this_evolution: dict[int, list[int]] = {ch: [] for ch in covered}
    halts = transitions = 0
    # stop stepping while another evolution still comes before the run ends
    chart_tasks = {ch["task"] for ch in m.charts}
    last_tick = (duration_ms * 1000 // m.tick_us - 1
                 - max(t["period_us"] // m.tick_us for t in m.tasks if t["id"] in chart_tasks))
    while True:
        c.step("chart")
        f = fw.wait_halted(c)
        if f.tick > last_tick:
            break
        halts += 1
        chart = f.location.a
        if f.location.kind == K.P_TRANSITION:
            tr = covered[chart]["transitions"][f.location.b]
            assert set(tr["sources"]) <= before[chart], (f.tick, tr, before[chart])
            this_evolution[chart].append(f.location.b)
            expected[chart] = f.location.b
            transitions += 1
        elif f.location.kind == K.P_CHART_END and chart in covered:
            after = active(chart)
            for t in this_evolution[chart]:
                assert set(covered[chart]["transitions"][t]["targets"]) <= after, (f.tick, t, after)
            assert this_evolution[chart] == sorted(this_evolution[chart])  # the documented firing order
            before[chart], this_evolution[chart] = after, []
        values = read([fired_items[ch] for ch in covered])
        assert dict(zip(covered, values)) == expected, (f.tick, f.location, values, expected)
    assert halts >= 10 and transitions >= 1, (halts, transitions)
    c.bp_clear()
    c.run()
    assert fw.wait_exit(timeout=60)[0] == 0
