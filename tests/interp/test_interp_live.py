"""Live replacement: a model edited while it runs swaps in at the next
instant; what did not change keeps its state; a broken edit is refused
and the run goes on.

tests/interp/data/live.elab runs a MovingAverage (`avg`) into a Gain (`g`)
every 10 ms under a chart, and an Integrator (`acc`) every 30 ms. The edit
doubles the gain and adds a Limit after it. Reference runs of the
unedited model give what must not change (the average, the chart, the
integrator's tally); the edited outputs are checked against the formula.
"""

from __future__ import annotations

import contextlib
import csv
import io
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from easylab.interp import Engine, PluginCache, PluginError
from easylab.interp.stimulus import load as load_stimulus
from easylab.interp.trace import TraceWriter, columns_of
from interp_testlib import DATA, lower

LIVE = (DATA / "live.elab").read_text()
STIMULUS = DATA / "live.stimulus.csv"
EDITED = LIVE.replace("g   = Gain<int16>(k = 1000)", "g   = Gain<int16>(k = 2000)\n"
                                                       "    lim = Limit<int16>(min = -1000, max = 500)") \
             .replace("g.y          -> out", "g.y   -> lim.x\n    lim.y -> out")
BROKEN = LIVE.replace("g.y          -> out", "g.y   -> nowhere")
DEBUG = "debug on uart0\n"  # the debug interface, for the tests that send models over it


def edited_out(smooth: int) -> int:
    return max(-1000, min(500, 2 * smooth))


def write_model(path: Path, text: str) -> Path:
    """Replace a model file at once (as editors save), so a poll never
    sees half a file."""
    temp = path.with_suffix(".tmp")
    temp.write_text(text)
    temp.replace(path)
    return path


def rows(trace: Path) -> dict[int, dict]:
    """A CSV trace as {time_us: row}, every 10 ms filled in (a row holds
    until the next one)."""
    table = {int(r["time_us"]): r for r in csv.DictReader(io.StringIO(trace.read_text()))}
    filled, last = {}, None
    for t in range(0, max(table) + 10000, 10000):
        last = table.get(t, last)
        filled[t] = last
    return filled


def run(program, trace: Path, duration_us: int, swaps=()):
    """Run ``program`` in-process, calling replace_model(new) after
    ``instants`` instants for each (instants, new) of ``swaps``; returns the
    engine (shut down) and the replacement reports."""
    reports = []
    writer = TraceWriter(str(trace), program, columns_of(program))
    engine = Engine(program, PluginCache(), load_stimulus(str(STIMULUS), program), writer,
                    on_replace=reports.append)
    done = 0
    for instants, new in swaps:
        engine.run(instants=instants - done)
        done = instants
        engine.replace_model(new)
    engine.run(duration_us)
    engine.shutdown()
    return engine, reports


@pytest.fixture(scope="module")
def programs(tmp_path_factory):
    d = tmp_path_factory.mktemp("live_models")
    return {name: lower(write_model(d / f"{name}.elab", text))
            for name, text in (("live", LIVE), ("edited", EDITED))}


@pytest.fixture(scope="module")
def reference(programs, tmp_path_factory):
    """The unedited model's trace over 30 s (the stimulus holds its last
    value after 10 s)."""
    trace = tmp_path_factory.mktemp("live_ref") / "ref.csv"
    run(programs["live"], trace, 30_000_000)
    return rows(trace)


def test_replacement_at_the_next_instant(programs, reference, tmp_path):
    trace = tmp_path / "live.csv"
    # 58 instants (0 .. 570 ms) processed, then the edit: it swaps in at
    # 580 ms, while the 30 ms task released at 570 ms is still pending.
    engine, reports = run(programs["live"], trace, 2_000_000, swaps=[(58, programs["edited"])])
    (report,) = reports
    assert report.time_us == 580_000
    assert (report.old_id, report.new_id) == (programs["live"].program_id, programs["edited"].program_id)
    assert sorted(report.kept_actors) == ["Filter.avg", "Tally.acc", "Tally.one"]
    assert sorted(report.new_actors) == ["Filter.g", "Filter.lim"]
    assert report.dropped_actors == ["Filter.g"]
    assert report.kept_charts == ["Mode"] and report.carried_tasks == ["slow"]
    # No activation lost or repeated.
    assert engine.activations == {"filter": 200, "slow": 67}

    live = rows(trace)
    assert max(live) == 1_990_000
    for t, row in live.items():
        ref = reference[t]
        # The average keeps its window, the chart its step (no re-entry),
        # the integrator its sum, and the pending activation's output arrives.
        for column in ("smooth", "entries", "tally", "Mode.active", "sensor.value"):
            assert row[column] == ref[column], (t, column)
        # The activation released at 580 ms is the first of the new model;
        # its outputs are published at 590 ms.
        expected = int(ref["out"]) if t < 590_000 else edited_out(int(ref["smooth"]))
        assert int(row["out"]) == expected, t
    assert {r["Mode.active"] for r in live.values()} == {"", "Low", "High"}
    assert any(edited_out(int(r["smooth"])) == 500 for r in live.values())  # the new Limit acts


def test_refused_plugin_keeps_the_run_going(programs, reference, tmp_path):
    """A model whose actor C code does not compile is refused by
    replace_model; the old model runs on, undisturbed."""
    bad = tmp_path / "bad.elab"
    write_model(bad, LIVE.replace(
        "dataflow Tally {", "actor type Bad() {\n    out y: int32\n    step {{ y = ; }}\n}\n\ndataflow Tally {\n"
                            "    bad = Bad()\n    sink = Add<int32>()\n    bad.y -> sink.a\n    bad.y -> sink.b"))
    program = lower(bad)
    trace = tmp_path / "live.csv"
    writer = TraceWriter(str(trace), programs["live"], columns_of(programs["live"]))
    engine = Engine(programs["live"], PluginCache(), load_stimulus(str(STIMULUS), programs["live"]), writer)
    engine.run(instants=30)
    with pytest.raises(PluginError, match="actor type 'Bad'"):
        engine.replace_model(program)
    engine.run(2_000_000)
    engine.shutdown()
    assert rows(trace) == {t: row for t, row in reference.items() if t < 2_000_000}


def test_what_changed_starts_afresh(programs, tmp_path):
    """A renamed step restarts its chart; a removed dataflow's actors are
    stopped and its var keeps its last traced value; a new var is not
    traced (the trace keeps its columns); a var whose declaration changed
    takes its new initial value."""
    text = LIVE.replace("step High", "step Upper").replace("-> High", "-> Upper").replace("High ->", "Upper ->") \
               .replace("var tally:   int32", "var extra:   bool = true") \
               .replace("var entries: uint16", "var entries: uint16 = 100")
    text = re.sub(r"dataflow Tally \{.*?\n\}\n", "", text, flags=re.S).replace("task slow   period 30 ms { run Tally }", "")
    program = lower(write_model(tmp_path / "changed.elab", text))
    trace = tmp_path / "live.csv"
    engine, (report,) = run(programs["live"], trace, 1_000_000, swaps=[(40, program)])
    assert report.restarted_charts == ["Mode"] and report.kept_charts == []
    assert sorted(report.dropped_actors) == ["Tally.acc", "Tally.one"]
    assert report.reset_items == ["entries"] and "smooth" in report.kept_items
    assert report.untraced == ["extra"] and report.frozen == ["tally"]
    live = rows(trace)
    assert len({live[t]["tally"] for t in live if t >= 400_000}) == 1  # frozen at its last value
    # The restarted chart entered its initial step again from the new initial value.
    assert int(live[410_000]["entries"]) == 101
    assert engine.activations["filter"] == 100


@contextlib.contextmanager
def easylab_run(errors: Path, *args):
    """`easylab run ARGS` (stderr into ``errors``) for the body of a with
    statement; then, 0.4 s later, SIGINT ends it with status 0 (killed if
    the body failed)."""
    with open(errors, "w") as err:
        proc = subprocess.Popen([sys.executable, "-m", "easylab", "run", *map(str, args)], stderr=err,
                                stdout=subprocess.DEVNULL)
    try:
        yield proc
        time.sleep(0.4)
        proc.send_signal(signal.SIGINT)
        assert proc.wait(20) == 0
    finally:
        if proc.poll() is None:
            proc.kill()


def _wait_for(path: Path, pattern: str, timeout: float) -> re.Match:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = re.search(pattern, path.read_text() if path.exists() else "")
        if m:
            return m
        time.sleep(0.05)
    raise AssertionError(f"no {pattern!r} within {timeout} s; stderr:\n{path.read_text()}")


def test_watch_command_line(programs, reference, tmp_path):
    """`easylab run --watch` in real time: a broken edit is
    reported and refused, the good edit swaps in at the next instant, and
    SIGINT ends the run with a complete trace."""
    model = write_model(tmp_path / "live.elab", EDITED)
    new_id = lower(model).program_id  # ids depend on the file's path: lower this one
    PluginCache().load_all(lower(model).specs)  # compiled already: the swap is quick
    write_model(model, LIVE)
    old_id = lower(model).program_id
    trace, errors = tmp_path / "live.csv", tmp_path / "stderr.txt"
    with easylab_run(errors, model, "--watch", "--duration", "60s", "--stimulus", STIMULUS,
                     "--trace", trace) as proc:
        deadline = time.monotonic() + 20
        while not trace.exists() and time.monotonic() < deadline:  # created when the run starts
            time.sleep(0.05)
        time.sleep(0.3)
        write_model(model, BROKEN)
        _wait_for(errors, r"still running program 0x[0-9a-f]{8}", 20)
        assert proc.poll() is None  # refused without stopping the run
        write_model(model, EDITED)
        changed = _wait_for(errors, r"at (\d+\.\d+) s the program id changed from (0x[0-9a-f]{8}) to "
                                    r"(0x[0-9a-f]{8})", 20)
    text = errors.read_text()
    assert "'nowhere'" in text and "Traceback" not in text
    check_swap(changed, old_id, new_id, rows(trace), reference)


def check_swap(changed: re.Match, old_id: int, new_id: int, live: dict, reference: dict) -> None:
    """The run's "program id changed" line names the two programs; the
    trace is the reference's until the swap and the edited model's after
    it, with the untouched actors' state (average, chart, tally) intact."""
    assert (changed.group(2), changed.group(3)) == (f"0x{old_id:08x}", f"0x{new_id:08x}")
    swap_us = round(float(changed.group(1)) * 1e6)
    assert swap_us % 10000 == 0 and swap_us + 200_000 <= max(live) < 30_000_000
    for t, row in live.items():
        ref = reference[t]
        for column in ("smooth", "entries", "tally", "Mode.active"):
            assert row[column] == ref[column], (t, column)
        expected = int(ref["out"]) if t <= swap_us else edited_out(int(ref["smooth"]))
        assert int(row["out"]) == expected, t


def test_replacement_over_the_debug_link(programs, reference, tmp_path):
    """The debugger sends models to `easylab run --debug` (LOAD_*, the
    console's `load`): a broken one is refused with the checker's message
    while the run goes on; the edited one swaps in at the next instant, the
    debug link and its client stay connected, the program id and the maps
    change, and the trace shows the new behaviour from the next activation
    on with the untouched actors' state intact."""
    from easylab.host_tools.debug_map import DebugMap
    from easylab.host_tools.debug_protocol import DebugClient

    model = write_model(tmp_path / "live.elab", LIVE + DEBUG)
    old_id = lower(model).program_id
    trace, errors, link, maps = tmp_path / "live.csv", tmp_path / "stderr.txt", tmp_path / "dbg", tmp_path / "maps"
    with easylab_run(errors, model, "--duration", "60s", "--stimulus", STIMULUS, "--trace", trace,
                     "--debug", f"pty:{link}", "--maps", maps) as proc:
        deadline = time.monotonic() + 60
        while not link.exists() and time.monotonic() < deadline:
            assert proc.poll() is None, errors.read_text()
            time.sleep(0.05)
        client = DebugClient.open(str(link), 2.0)
        assert client.hello().program_id == old_id == DebugMap.load(maps / "debug_map.json").program_id
        same = client.replace_model((LIVE + DEBUG).encode())  # the running model: nothing to swap
        assert (same.state, same.program_id, same.message) == ("replaced", old_id, "unchanged: the running program")
        refused = client.replace_model((BROKEN + DEBUG).encode())
        assert refused.state == "refused" and "'nowhere'" in refused.message
        assert proc.poll() is None and client.program_id() == old_id
        status = client.replace_model((EDITED + DEBUG).encode())
        assert status.state == "replaced" and status.program_id != old_id
        assert client.hello().program_id == status.program_id == DebugMap.load(maps / "debug_map.json").program_id
        client.close()
    text = errors.read_text()
    assert "refused" in text and "Traceback" not in text
    changed = re.search(r"at (\d+\.\d+) s the program id changed from (0x[0-9a-f]{8}) to (0x[0-9a-f]{8})", text)
    check_swap(changed, old_id, status.program_id, rows(trace), reference)


def test_firmware_refuses_to_load_a_model(tmp_path):
    """LOAD_* are board commands: a firmware (the host board's) answers
    E_UNKNOWN_CMD, and the console says what to do instead."""
    from easylab.build import build
    from easylab.host_tools.debug_protocol import DebugClient, DebugError, K

    model = write_model(tmp_path / "live.elab", LIVE + DEBUG)
    exe = build(lower(model), "host", tmp_path / "fw").executable
    link = tmp_path / "dbg"
    proc = subprocess.Popen([str(exe), "--debug", f"pty:{link}", "--duration", "2s"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 10
        while not link.exists() and time.monotonic() < deadline:
            time.sleep(0.02)
        client = DebugClient.open(str(link), 2.0)
        client.hello()
        with pytest.raises(DebugError) as err:
            client.send_model((LIVE + DEBUG).encode())
        assert err.value.status == K.E_UNKNOWN_CMD
        client.close()
    finally:
        proc.kill()
        proc.wait()
