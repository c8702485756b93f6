"""The shipped examples check clean (library call and CLI), and what the
checker makes of them is right in the places that are easy to get wrong."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest

from easylab.core import types as T
from easylab.pipeline import check_file

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples").glob("*.elab"))
# A single-file example in a folder of its own (the other folders need their drivers or nodes).
FOLDER_EXAMPLES = [ROOT / "examples" / "vision_line" / "vision_line.elab"]
ALL_FEATURES = Path(__file__).parent / "models" / "all_features.elab"


def _model(name: str):
    result = check_file(ROOT / "examples" / f"{name}.elab")
    assert result.model is not None, result.report()
    return result.model


def test_there_are_examples():
    assert len(EXAMPLES) >= 5


@pytest.mark.parametrize("path", [*EXAMPLES, *FOLDER_EXAMPLES, ALL_FEATURES], ids=lambda p: p.stem)
def test_example_checks_clean(path):
    result = check_file(path)
    assert result.diagnostics.sorted() == [], result.report()
    assert result.model is not None
    assert result.report() == ""


@pytest.mark.parametrize("path", [*EXAMPLES, *FOLDER_EXAMPLES], ids=lambda p: p.stem)
def test_example_checks_clean_through_the_cli(cli, path):
    proc = cli("check", path.relative_to(ROOT))
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    assert proc.stdout.startswith(f"{path.relative_to(ROOT)}: ok")


def test_cli_checks_all_examples_at_once(cli):
    proc = cli("check", "-q", *(p.relative_to(ROOT) for p in [*EXAMPLES, *FOLDER_EXAMPLES]))
    assert (proc.returncode, proc.stdout, proc.stderr) == (0, "", "")


# ------------------------------------------------------------ pt100_sensor


def test_pt100_infers_the_moving_average_type_from_the_device():
    acquire = _model("pt100_sensor").dataflows["Acquire"]
    avg = acquire.instances["avg"]
    assert avg.type_bindings == {"T": T.UINT16}
    assert avg.port_types == {"x": T.UINT16, "y": T.UINT16}
    assert avg.state_types["window"] == (T.UINT16, 8)  # T[n] with the default n = 8
    assert avg.args["n"].const == 8
    assert acquire.instances["hyst"].type_bindings == {"T": T.INT16}  # explicit


def test_pt100_device_data_alias():
    m = _model("pt100_sensor")
    raw = m.device_data["sensor.raw"]
    assert raw is m.device_data["sensor.adc.value"]  # the re-export is the part's datum
    assert raw.name == "sensor.raw"  # named by its shortest path
    assert (raw.type, raw.port.direction, raw.device.path, raw.device.driver) == \
        (T.UINT16, "out", "sensor.adc", "analog_in")
    [edge] = [e for e in m.dataflows["Acquire"].edges if e.dst.label == "avg.x"]
    assert edge.src.kind == "device" and edge.src.target is raw


def test_pt100_params_feed_actor_parameters():
    cal = _model("pt100_sensor").dataflows["Acquire"].instances["cal"]
    assert cal.args["gain"].const is None and cal.args["gain"].params == ("cal_gain",)
    assert cal.args["offset"].params == ("cal_offset",)


def test_pt100_channel_tasks_and_interfaces():
    m = _model("pt100_sensor")
    samples = m.channels["samples"]
    assert samples.initial_tokens == (0,) * 100
    assert [e.label for e in samples.producers] == ["cal.y -> samples"]
    assert [e.label for e in samples.consumers] == ["samples -> stats.x"]
    assert {n: (t.period_us, t.offset_us, t.deadline_us) for n, t in m.tasks.items()} == {
        "acquire": (10_000, 0, 10_000), "statistics": (1_000_000, 0, 1_000_000)}
    assert m.dataflows["Acquire"].task is m.tasks["acquire"]
    assert [(i.kind, i.settings) for i in m.interfaces] == [
        ("debug", {"baud": 115200}), ("modbus-rtu", {"baud": 19200, "parity": "even", "unit": 17})]
    p = m.data["cal_gain"]
    assert (p.kind, p.type, p.initial, p.range, p.decl.persist, p.decl.service.access) == \
        ("param", T.INT16, 1000, (500, 2000), True, "rw")
    assert m.data["cal_offset"].range == (-500, 500)


# ------------------------------------------------------------ line_follower


def test_line_follower_chart_parallel_branches():
    m = _model("line_follower")
    chart = m.charts["Mission"]
    assert chart.initial.name == "Idle"
    branches = {name: step.branch for name, step in chart.steps.items()}
    divergence = chart.transitions[0]
    assert [s.name for s in divergence.targets] == ["Drive", "Monitor"]
    left, right = ((divergence.index, 0),), ((divergence.index, 1),)
    assert branches == {"Idle": (), "Drive": left, "DriveDone": left, "Monitor": right, "MonitorDone": right}
    convergence = chart.transitions[3]
    assert [s.name for s in convergence.sources] == ["DriveDone", "MonitorDone"]
    assert [s.name for s in convergence.targets] == ["Idle"]
    assert [df.name for df in chart.steps["Idle"].runs] == ["Halt", "Watch"]
    # the chart's task owns the dataflows its steps run
    assert chart.task is m.tasks["control"]
    assert {df.task.name for df in (m.dataflows["Halt"], m.dataflows["Watch"], m.dataflows["FollowLine"])} == \
        {"control"}


def test_line_follower_composed_devices():
    m = _model("line_follower")
    assert [d.path for d in m.devices] == [
        "robot.drive.m1", "robot.drive.m2", "robot.drive.m3", "robot.front", "robot.left", "robot.right",
        "robot.camera", "robot.bumper"]
    assert {str(c): c.owner for c in m.claims} == {
        'pwm["PE3"]': "robot.drive.m1", 'pin["PA0"]': "robot.drive.m1", 'pwm["PE4"]': "robot.drive.m2",
        'pin["PA1"]': "robot.drive.m2", 'pwm["PE5"]': "robot.drive.m3", 'pin["PA2"]': "robot.drive.m3",
        "adc[0]": "robot.front", "adc[1]": "robot.left", "adc[2]": "robot.right", "uart[2]": "robot.camera",
        'pin["PD0"]': "robot.bumper", "uart[0]": "debug", "uart[1]": "modbus rtu"}
    speed = m.device_data["robot.drive.m2.speed"]
    assert (speed.type, speed.port.direction, speed.device.driver) == (T.INT16, "in", "motor")
    assert m.device_data["robot.camera.offset"].type is T.INT16  # `offset` is a name here
    # the three motor inputs are written by two dataflows of one task
    assert [w.owner.name for w in speed.writers] == ["FollowLine", "Halt"]


def test_line_follower_explicit_type_arguments_and_params():
    follow = _model("line_follower").dataflows["FollowLine"]
    pid = follow.instances["pid"]
    assert pid.type_bindings == {"T": T.INT16}
    assert pid.args["kp"].params == ("steer_kp",)
    assert (pid.args["out_min"].const, pid.args["out_max"].const) == (-255, 255)


# ------------------------------------------------------------ the others


def test_pneumatic_cylinder_chart_and_time_param():
    m = _model("pneumatic_cylinder")
    chart = m.charts["Cylinder"]
    assert chart.initial.name == "Retracted"
    assert all(step.branch == () for step in chart.steps.values())
    assert [(t.sources[0].name, t.targets[0].name) for t in chart.transitions] == [
        ("Retracted", "Extending"), ("Extending", "Extended"), ("Extending", "Fault"),
        ("Extended", "Retracting"), ("Retracting", "Retracted"), ("Retracting", "Fault"),
        ("Fault", "Retracting")]
    timeout = m.data["timeout"]
    assert (timeout.type, timeout.initial, timeout.range) == (T.TIME, 2_000_000, (100_000, 10_000_000))
    # `alarm` is written by the chart (control task) only; the Lamp dataflow reads it
    assert [type(w.owner).__name__ for w in m.data["alarm"].writers] == ["ChartInfo", "ChartInfo"]
    pos = m.dataflows["PositionControl"].instances["pos"]
    assert pos.type_bindings == {"A": T.UINT16, "B": T.INT16}


def test_cd_to_dat_rates():
    convert = _model("cd_to_dat").dataflows["Convert"]
    assert {n: i.port_rates for n, i in convert.instances.items()} == {
        "src": {"y": 1}, "b": {"x": 1, "y": 2}, "c": {"x": 3, "y": 2}, "d": {"x": 7, "y": 8},
        "e": {"x": 7, "y": 5}, "f": {"x": 1, "y": 1}, "sum": {"x": 160, "y": 1}}
    assert _model("cd_to_dat").tasks["convert"].period_us == Fraction(20_000)


def test_blink_drives_the_led_from_a_param():
    m = _model("blink")
    wave = m.dataflows["Blink"].instances["wave"]
    assert wave.args["half_period"].params == ("half_period",)
    [edge] = m.dataflows["Blink"].edges
    assert (edge.src.label, edge.dst.label, edge.dst.kind) == ("wave.y", "led.level", "device")
    assert m.device_data["led.level"].writers[0].owner is m.dataflows["Blink"]
    assert m.name == "blink" and m.title == "Blink an LED"


# ------------------------------------------------------------ every feature once


def test_all_features_model():
    result = check_file(ALL_FEATURES)
    m = result.model
    assert m is not None, result.report()
    assert (m.consts["HALF"].value, m.consts["WINDOW"].value) == (506, 8)
    acquire = m.dataflows["Acquire"]
    assert (acquire.decl.schedule, m.dataflows["Report"].decl.schedule) == ("min-buffer", "sas")
    acc = acquire.instances["acc"]
    assert acc.type_bindings == {"T": T.INT16, "U": T.INT32}
    assert acc.port_rates == {"x": 4, "y": 1, "total": 1}
    assert acc.state_types == {"history": (T.INT16, 8), "acc": (T.INT32, None)}
    assert {n: a.const for n, a in acc.args.items()} == {"n": 4, "k": 2}
    assert acquire.instances["pick"].args["op"].const == "min"
    assert acquire.instances["gain_stage"].args["k"].params == ("gain",)
    assert {e.label: e.initial_tokens for e in acquire.edges if e.initial_tokens} == {
        "pick.y -> lim.x": (0,), "gain_stage.y -> pick.b": (7,)}
    assert m.channels["blocks"].initial_tokens == (1, 2, 3, 4, 5, 6, 7, 8)
    assert {n: (d.type.name, d.initial, d.range) for n, d in m.data.items()} == {
        "gain": ("int16", 1000, (0, 2024)), "limit": ("float32", Fraction(3, 2), (0, 1000)),
        "timeout": ("time", 2_000_000, (100_000, 10_000_000)), "level": ("int16", -5, None),
        "ready": ("bool", True, None), "count": ("uint32", 0, None), "mode": ("uint8", 0, None),
        "filtered": ("int16", 0, None), "summary": ("int16", 0, None)}
    data = m.device_data["station.data"]
    assert data is m.device_data["station.probe.samples"] and data.port.rate == 4
    assert m.device_data["station.light"].name == "station.light"
    assert (m.device_data["station.light"].safe, m.device_data["station.fan.duty"].safe) == (True, 100)
    assert m.device_data["station.data"].safe is None  # an out datum has none
    assert (m.remote.watchdog_us, m.remote.overrun_limit) == (150_000, 4)
    assert {str(c): c.owner for c in m.claims} == {
        "adc[3]": "station.probe", 'pin["PC3"]': "station.lamp", 'pwm["PD5"]': "station.fan",
        'pin["PB0"]': "button", "uart[0]": "debug", "uart[1]": "modbus rtu"}
    assert [(i.kind, i.settings) for i in m.interfaces] == [
        ("debug", {"baud": 57600}), ("modbus-rtu", {"baud": 9600, "parity": "odd", "unit": 3}),
        ("modbus-tcp", {"port": 1502, "unit": 9})]
    assert {n: (t.period_us, t.offset_us, t.deadline_us, t.wcet_us) for n, t in m.tasks.items()} == {
        "acquire": (2000, 0, 2000, None), "control": (10_000, 1000, 8000, 500), "report": (16_000, 1000, 16_000, None)}
    assert {n: s.branch for n, s in m.charts["Sequence"].steps.items()} == {
        "Idle": (), "Work": ((0, 0),), "Watch": ((0, 1),), "WorkDone": ((0, 0),), "WatchDone": ((0, 1),)}


def test_schedule_kinds_in_the_model_and_their_errors():
    """`schedule flat` is the flat single-appearance schedule; a dataflow
    that has none is an error at its name, and sas schedules it."""
    from easylab.analysis.dataflow import analyze_dataflow
    from easylab.core.source import Diagnostics

    model = Path(__file__).parent / "models" / "no_flat_schedule.elab"
    result = check_file(model)
    (d,) = result.diagnostics.sorted()
    assert (d.span.line, d.span.column) == (20, 10)
    assert "dataflow 'D': this graph has no flat single-appearance schedule" in d.message
    good = check_file(model, schedule="sas")
    assert good.model is not None and str(good.model.dataflows["D"].analysis.result.schedule) == "t(2pq)"
    cd = check_file(ROOT / "examples" / "cd_to_dat.elab", schedule="flat").model.dataflows["Convert"]
    assert str(cd.analysis.result.schedule) == "(147 src) (147 b) (98 c) (28 d) (32 e) (160 f) sum out:checksum"
    assert analyze_dataflow(cd, Diagnostics(), "flat").result.buffer_total == 1182  # 1181 + the output token
