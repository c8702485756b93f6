"""Local execution of devices whose types bring host handlers: each a
plug-in, run at the instants the firmware runs them, sampled from the
stimulus first, kept or restarted across a live replacement; the same
trace as the host firmware."""

from __future__ import annotations

from textwrap import dedent

from easylab.interp import Engine, PluginCache, PluginError
from easylab.interp.stimulus import load as load_stimulus
from easylab.interp.trace import TraceWriter, columns_of
from easylab.pipeline import lower_file

from handlers_testlib import build, run, write_model

MODEL = dedent("""\
    model counter
    import std
    // A host handler that counts its reads in its state, reports the count,
    // scales the stimulus and sees its input at each write.
    device type Tally(k: int16 = 2) {
        out count: uint16
        out scaled: int16
        in seen: int16
        state reads: uint16
        state opened: uint16
        state last_written: int16
        driver "counter" impl host "counter_host.c"
    }
    device c: Tally(k = 3)
    var n: uint16
    var s: int16
    dataflow D { c.count -> n  c.scaled -> s  c.scaled -> c.seen }
    task t period 10 ms { run D }
    """)
HANDLERS = dedent("""\
    EL_OPEN { opened++; }
    EL_READ {
        reads++;
        count = (uint16_t)(reads + 100u * opened);
        scaled = (int16_t)(scaled * k + last_written);
    }
    EL_WRITE { last_written = (int16_t)(seen % 7); }
    """)


def _engine(program, tmp_path, name):
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,c.scaled\n0,5\n30000,-4\n")
    writer = TraceWriter(str(tmp_path / name), program, columns_of(program))
    return Engine(program, PluginCache(tmp_path / "cache"), load_stimulus(str(stim), program), writer)


def test_host_handlers_run_locally_as_in_the_host_firmware(tmp_path):
    path = write_model(tmp_path, MODEL, {"counter_host.c": HANDLERS})
    program, result = lower_file(path)
    assert program is not None, result.report()
    engine = _engine(program, tmp_path, "local.csv")
    engine.run(60000)
    engine.shutdown()
    built = build(path, "host", tmp_path / "host")
    run(built.executable, "--fast", "--duration", "60ms", "--stimulus", tmp_path / "s.csv",
        "--trace", tmp_path / "host.csv")
    assert (tmp_path / "local.csv").read_bytes() == (tmp_path / "host.csv").read_bytes()
    lines = (tmp_path / "host.csv").read_text().splitlines()
    assert lines[1].startswith("0,0,0,101,15,")  # the first read: count 1 + 100 (opened once), 5 * 3


def test_without_a_trace_the_instants_of_a_device_with_handlers_still_run_them(tmp_path):
    """Without a trace the runner takes stretches of instants alone; the
    instants that read or write a device with host handlers stay Python's."""
    path = write_model(tmp_path, MODEL, {"counter_host.c": HANDLERS})
    program, result = lower_file(path)
    assert program is not None, result.report()
    finals = []
    for writer in (TraceWriter(str(tmp_path / "t.csv"), program, columns_of(program)), None):
        stim = tmp_path / "s.csv"
        stim.write_text("time_us,c.scaled\n0,5\n30000,-4\n")
        engine = Engine(program, PluginCache(tmp_path / "cache"), load_stimulus(str(stim), program), writer)
        engine.run(60000)
        finals.append([list(a) for a in engine.state.published])
        engine.shutdown()
    assert finals[0] == finals[1]
    count = next(i.id for i in program.items if i.name == "n")
    assert finals[1][count] == [105]  # five reads published (0..40 ms) + 100 (opened once)


def test_a_replacement_keeps_an_unchanged_devices_state_and_restarts_a_changed_one(tmp_path):
    path = write_model(tmp_path, MODEL, {"counter_host.c": HANDLERS})
    program, _ = lower_file(path)
    # The model edited (a var more, the device a line lower), then its device's handler file changed.
    same, _ = lower_file(write_model(tmp_path, MODEL.replace("import std", "import std\nvar unused: int8")))
    (tmp_path / "counter_host2.c").write_text(HANDLERS.replace("reads++;", "reads += 2u;"))
    changed, _ = lower_file(write_model(tmp_path, MODEL.replace("counter_host.c", "counter_host2.c")))
    engine = _engine(program, tmp_path, "t.csv")
    engine.run(instants=3)
    engine.replace_model(same)
    engine.run(instants=2)
    kept = engine.state.published[engine.program.item("c.count").id][0]
    assert kept == 105  # 5 reads, opened once: the device went on
    engine.replace_model(changed)
    engine.run(instants=2)
    restarted = engine.state.published[engine.program.item("c.count").id][0]
    assert restarted == 2 * 2 + 100  # a new plug-in: fresh state, opened again, two reads of 2
    engine.shutdown()


def test_a_host_handler_file_that_does_not_compile_names_the_device(tmp_path):
    path = write_model(tmp_path, MODEL, {"counter_host.c": "EL_READ { nonsense(); }\n"})
    program, _ = lower_file(path)
    try:
        Engine(program, PluginCache(tmp_path / "cache"))
    except PluginError as err:
        assert str(err).startswith("device 'c' (Tally, ") and "its C code does not compile" in str(err)
    else:
        raise AssertionError("the plug-in should not build")
