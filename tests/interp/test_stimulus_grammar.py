"""The two stimulus readers, the host program's (boards/host/host_stimulus.c)
and easylab run's (generator/interp/stimulus.py), follow one grammar
(boards/host/README.md, "Stimulus CSV"): fed the same files, well-formed or
not, they accept the same ones and refuse the others at the same line."""

from __future__ import annotations

import re
import subprocess

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from easylab.interp import stimulus
from easylab.pipeline import lower_file
from firmware_builds import ROOT, build, write_model

MODEL = """model stim "t"
import std
device sensor: Pt100(channel = 0)
param gain: int16 = 1000 range 500..2000
param level: float32 = 0.5 range -1.0..2.5
param big: uint32 = 7
param on: bool = false
param wait: time = 10 ms range 1 ms..5 s
param small: int8 = 0
var out: uint16
dataflow D {
    avg = MovingAverage(n = 8)
    sensor.raw -> avg.x
    avg.y -> out
}
task main period 1 ms { run D }
"""
COLUMNS = ["gain", "level", "big", "on", "wait", "small", "out", "sensor.raw"]


@pytest.fixture(scope="module")
def readers(tmp_path_factory):
    """verdict(data) -> (C's, Python's): each None (accepted) or the line
    number of the refusal."""
    folder = tmp_path_factory.mktemp("stim")
    path = write_model(folder, MODEL)
    exe = build(path, "host", folder / "out").executable
    program, result = lower_file(path)
    assert program is not None, result.report()
    csv = folder / "s.csv"

    def verdict(data: bytes):
        csv.write_bytes(data)
        proc = subprocess.run([str(exe), "--fast", "--duration", "1ms", "--stimulus", str(csv)],
                              capture_output=True, timeout=60, stdin=subprocess.DEVNULL)
        assert proc.returncode in (0, 2), proc.stderr
        c_line = None
        if proc.returncode == 2:
            m = re.match(rb".*?s\.csv:(\d+): ", proc.stderr)
            assert m, proc.stderr
            c_line = int(m.group(1))
        try:
            stimulus.load(str(csv), program)
            py_line = None
        except stimulus.StimulusError as err:
            py_line = int(re.match(r".*?s\.csv:(\d+): ", str(err)).group(1))
        return c_line, py_line

    return verdict


HEADER = "time_us," + ",".join(COLUMNS) + "\n"
BLANK = "," * len(COLUMNS)

# Cells and files found to part the two readers, and their neighbours.
FILES = {
    "unicode digits in a value": HEADER + "0,1\u0663" + BLANK[1:] + "\n",
    "full-width digit": HEADER + "0," + "\uff11" + BLANK[1:] + "\n",
    "unicode digits in a time": HEADER + "\u0663" + BLANK + "\n",
    "a 5000-digit value": HEADER + "0," + "9" * 5000 + BLANK[1:] + "\n",
    "a 5000-digit time": HEADER + "9" * 5000 + BLANK + "\n",
    "a 5000-digit index": "time_us,sensor.raw[" + "9" * 5000 + "]\n0,1\n",
    "a param below its range": HEADER + "0,499" + BLANK[1:] + "\n",
    "a param above its range": HEADER + "0,2001" + BLANK[1:] + "\n",
    "a float param above its range": HEADER + "0,,2.6" + BLANK[2:] + "\n",
    "a float param NaN": HEADER + "0,,nan" + BLANK[2:] + "\n",
    "a time param above its range": HEADER + "0,,,,,5001" + BLANK[5:] + "\n",
    "a param at its bounds": HEADER + "0,500,-1.0,,,1" + BLANK[5:] + "\n1,2000,2.5,,,5000" + BLANK[5:] + "\n",
    "a vertical tab before a float": HEADER + "0,,\x0b1.0" + BLANK[2:] + "\n",
    "a form feed before a float": HEADER + "0,,\x0c1.0" + BLANK[2:] + "\n",
    "a huge hex float": HEADER + "0,,0x1p99999" + BLANK[2:] + "\n",
    "a unicode digit in an exponent": HEADER + "0,,1e\u0663" + BLANK[2:] + "\n",
}


@pytest.mark.parametrize("name", list(FILES))
def test_both_readers_give_the_same_verdict_on_known_files(readers, name):
    c, py = readers(FILES[name].encode("utf-8"))
    assert c == py, f"{name}: C {c}, Python {py}"


def test_a_param_outside_its_declared_range_is_refused_by_both(readers):
    assert readers(FILES["a param below its range"].encode()) == (2, 2)
    assert readers(FILES["a param at its bounds"].encode()) == (None, None)


def test_both_readers_cap_the_values_of_a_stimulus():
    """The Python reader's cap is the C reader's (host_internal.h)."""
    header = (ROOT / "boards/host/host_internal.h").read_text(encoding="utf-8")
    m = re.search(r"#define EL_HOST_STIMULUS_MAX_EVENTS \((\d+)ul \* 1024ul \* 1024ul\)", header)
    assert m and stimulus.MAX_VALUES == int(m.group(1)) * 1024 * 1024


CELLS = st.sampled_from(["", "0", "1", "-1", "+1", "500", "2000", "2001", "1.5", "-1.0", "2.5", "nan", "inf",
                         "-inf", "0x10", "0x1p3", "1e3", "1e", ".5", "5.", "true", "false", "\u0663", "\uff11",
                         "4294967295", "4294967296", "-129", "127", "9" * 30, " 7 ", "\t1", "\x0b1", "1_0",
                         "abc", "1,2", "\r", "00012", "-0", "1e-400", "3.5e38", "3.402823466e38"])
TIMES = st.sampled_from(["0"] * 8 + ["1", "1000", "5", "-1", "", "x", "18446744073709551615",
                                     "18446744073709551616", "\u0661", " 3 "])
NAMES = st.sampled_from(COLUMNS + ["sensor.raw[0]", "sensor.raw[1]", "nope", "", "gain ", "time_us", "out[0]",
                                   "sensor.raw[00]", "sensor.raw[\u0660]"])


@st.composite
def stimulus_files(draw) -> bytes:
    names = draw(st.lists(st.sampled_from(COLUMNS), min_size=1, max_size=2, unique=True))
    if not draw(st.integers(0, 7)):  # now and then a name of the wider set, often a wrong one
        names[draw(st.integers(0, len(names) - 1))] = draw(NAMES)
    header = ",".join(["time_us"] + names) if draw(st.integers(0, 9)) else ",".join(names)
    rows = []
    for _ in range(draw(st.integers(0, 3))):
        cells = [draw(TIMES)] + [draw(CELLS) for _ in range(len(names) + draw(st.sampled_from([0] * 12 + [1, -1])))]
        rows.append(",".join(cells))
    ending = draw(st.sampled_from(["\n", "\r\n"]))
    text = ending.join([header] + rows) + draw(st.sampled_from(["", ending]))
    return text.encode("utf-8")


@settings(max_examples=250, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(stimulus_files())
def test_both_readers_give_the_same_verdict_on_any_stimulus(readers, data):
    c, py = readers(data)
    assert c == py, f"{data!r}: C {c}, Python {py}"


@settings(max_examples=60, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(st.binary(max_size=200))
def test_both_readers_give_the_same_verdict_on_any_bytes_after_a_header(readers, tail):
    c, py = readers(HEADER.encode() + tail)
    assert c == py, f"{tail!r}: C {c}, Python {py}"


def test_a_stimulus_over_the_cap_is_refused_at_the_line_of_the_value_too_many(readers, monkeypatch, tmp_path):
    monkeypatch.setattr(stimulus, "MAX_VALUES", 3)
    path = write_model(tmp_path, MODEL)
    program, _ = lower_file(path)
    csv = tmp_path / "s.csv"
    csv.write_text("time_us,gain\n0,500\n1,600\n2,700\n3,800\n", encoding="utf-8")
    with pytest.raises(stimulus.StimulusError, match=r"s\.csv:5: more than 3 values: stimulus too big"):
        stimulus.load(str(csv), program)
