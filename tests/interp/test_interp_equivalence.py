"""Acceptance: `easylab run` gives the host-native firmware's trace, byte for
byte (CSV and VCD), for the same model, stimulus and duration.

Models: every example (with stimuli that drive its device data, params and
vars so that its charts move), tests/interp/data/charts.elab (chart
semantics), tests/interp/data/multirate.elab (dataflow semantics), and
random typed expressions (the C arithmetic).
"""

from __future__ import annotations


import pytest

from interp_testlib import DATA, EXAMPLES, ExprModel, run_host, run_interp

CASES = {
    # name: (model, stimulus or None, duration)
    "blink": (EXAMPLES / "blink.elab", DATA / "blink.stimulus.csv", "3s"),
    "cd_to_dat": (EXAMPLES / "cd_to_dat.elab", None, "3s"),
    "line_follower": (EXAMPLES / "line_follower.elab", DATA / "line_follower.stimulus.csv", "3s"),
    "pneumatic_cylinder": (EXAMPLES / "pneumatic_cylinder.elab", DATA / "pneumatic_cylinder.stimulus.csv", "3s"),
    "pt100_sensor": (EXAMPLES / "pt100_sensor.elab", EXAMPLES / "pt100_sensor.stimulus.csv", "3500ms"),
    "pt100_sensor-params": (EXAMPLES / "pt100_sensor.elab", DATA / "pt100_sensor.stimulus.csv", "3s"),
    "charts": (DATA / "charts.elab", DATA / "charts.stimulus.csv", "3s"),
    "multirate": (DATA / "multirate.elab", DATA / "multirate.stimulus.csv", "1500ms"),
}


@pytest.fixture(scope="module")
def firmware(host_firmware):
    host_firmware.prebuild(model for model, _, _ in CASES.values())
    return host_firmware


@pytest.mark.parametrize("ext", ["csv", "vcd"])
@pytest.mark.parametrize("name", list(CASES))
def test_same_trace_as_host_firmware(name, ext, firmware, tmp_path):
    model, stimulus, duration = CASES[name]
    host, interp = tmp_path / f"host.{ext}", tmp_path / f"interp.{ext}"
    run_host(firmware(model), host, duration, stimulus)
    assert run_interp(model, interp, duration, stimulus) == 0
    expected = host.read_bytes()
    assert interp.read_bytes() == expected
    if ext == "csv":
        assert expected.count(b"\n") > 20, "the stimulus should make the model move"


def test_charts_move(firmware, tmp_path):
    """The stimuli reach the interesting states (else equality proves little)."""
    seen = {}
    for name in ("line_follower", "pneumatic_cylinder", "charts"):
        model, stimulus, duration = CASES[name]
        trace = tmp_path / f"{name}.csv"
        assert run_interp(model, trace, duration, stimulus) == 0
        seen[name] = trace.read_text()
    for steps in ("Idle", "Drive+Monitor", "DriveDone+MonitorDone"):
        assert f",{steps}\n" in seen["line_follower"]
    for step in ("Extending", "Extended", "Retracting", "Fault"):
        assert f",{step}\n" in seen["pneumatic_cylinder"]
    for steps in ("Left+Right", "LeftWait+RightWait", "Alarm"):
        assert steps in seen["charts"]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_expressions(seed, host_firmware, tmp_path):
    gen = ExprModel(seed)
    model = tmp_path / "exprs.elab"
    model.write_text(gen.model())
    stimulus = tmp_path / "exprs.csv"
    stimulus.write_text(gen.stimulus(120))
    exe = host_firmware(model)
    for ext in ("csv", "vcd"):
        host, interp = tmp_path / f"host.{ext}", tmp_path / f"interp.{ext}"
        run_host(exe, host, "1200ms", stimulus)
        assert run_interp(model, interp, "1200ms", stimulus) == 0
        # Every NaN is printed "nan" by both: C leaves a NaN's sign to the
        # compiler (gcc rewrites a + (-b) as a - b), so traces do not show it.
        assert interp.read_bytes() == host.read_bytes()


@pytest.mark.parametrize("name, schedule", [("cd_to_dat", "min-buffer"), ("cd_to_dat", "flat"), ("multirate", "sas")])
def test_other_schedules(name, schedule, tmp_path):
    """`--schedule` changes the firmware's buffers (rings, or linear ones with
    delays and a self-loop), not the values."""
    from easylab.build import build
    from easylab.pipeline import lower_file

    model, stimulus, duration = CASES[name]
    program, result = lower_file(model, schedule=schedule)
    assert program is not None, result.report()
    exe = build(program, "host", tmp_path / "fw").executable
    host, interp = tmp_path / "host.vcd", tmp_path / "interp.vcd"
    run_host(exe, host, duration, stimulus)
    assert run_interp(model, interp, duration, stimulus, "--schedule", schedule) == 0
    assert interp.read_bytes() == host.read_bytes()
