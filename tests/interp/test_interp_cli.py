"""`easylab run`'s command line: the host board's input checks and messages,
exit statuses, real time."""

from __future__ import annotations

import subprocess
import time

import pytest

from interp_testlib import DATA, EXAMPLES, run_interp

MODEL = DATA / "multirate.elab"

BAD_STIMULI = {
    "unknown column": "time_us,nosuch\n0,1\n",
    "device in datum": "time_us,sink.levels\n",
    "index too big": "time_us,probe.samples[4]\n",
    "index of a scalar": "time_us,k[0]\n",
    "integer out of range": "time_us,k\n0,40000\n",
    "not an integer": "time_us,last\n0,1.5\n",
    "not a float": "time_us,probe.gain\n0,abc\n",
    "float out of range": "time_us,probe.gain\n0,1e39\n",
    "bad bool": "time_us,probe.gain,k\n0,1,true\n",
    "time going back": "time_us,k\n10,1\n5,2\n",
    "cell count": "time_us,k\n0,1,2\n",
    "empty file": "",
    "first column": "time,k\n",
    "same datum twice": "time_us,probe.samples,probe.samples[1]\n",
    "bad time": "time_us,k\n-1,2\n",
    "empty column name": "time_us,,k\n",
}


@pytest.mark.parametrize("case", list(BAD_STIMULI))
def test_stimulus_errors_are_the_host_boards(case, host_firmware, tmp_path, capsys):
    stimulus = tmp_path / "bad.csv"
    stimulus.write_text(BAD_STIMULI[case])
    host = subprocess.run([str(host_firmware(MODEL)), "--fast", "--duration", "10ms", "--stimulus", str(stimulus),
                           "--trace", str(tmp_path / "h.csv")], capture_output=True, text=True)
    trace = tmp_path / "i.csv"
    status = run_interp(MODEL, trace, "10ms", stimulus)
    assert (host.returncode, status) == (2, 2)
    assert capsys.readouterr().err == host.stderr
    assert not trace.exists() and not (tmp_path / "h.csv").exists()


def test_stimulus_format_details(host_firmware, tmp_path):
    """A byte-order mark, blanks around cells, CRLF, blank lines, hex and
    special floats, whole-item columns and a param column."""
    stimulus = tmp_path / "s.csv"
    stimulus.write_bytes(b"\xef\xbb\xbf time_us , probe.samples ,probe.gain,\tk\r\n"
                         b"0, 5 ,0x1.8p1,7\r\n\r\n  \n20000,,-INFINITY,\n40000,-3,nan(0x1),-9\n"
                         b"60000,,3.40282349e38,\n")
    host, interp = tmp_path / "h.csv", tmp_path / "i.csv"
    subprocess.run([str(host_firmware(MODEL)), "--fast", "--duration", "100ms", "--stimulus", str(stimulus),
                    "--trace", str(host)], check=True)
    assert run_interp(MODEL, interp, "100ms", stimulus) == 0
    assert interp.read_bytes() == host.read_bytes()
    assert b"3.40282347e+38" in host.read_bytes()  # just above FLT_MAX: rounds to it


@pytest.mark.parametrize("duration, why", [("10", "a duration needs a unit"), ("1.5x", "unknown time unit"),
                                           ("1.0000001ms", "finer than 1 us"), ("abc", "not a duration")])
def test_bad_duration(duration, why, tmp_path, capsys):
    assert run_interp(EXAMPLES / "blink.elab", tmp_path / "t.csv", duration) == 2
    assert why in capsys.readouterr().err
    assert not (tmp_path / "t.csv").exists()


def test_bad_trace_path(tmp_path, capsys):
    assert run_interp(EXAMPLES / "blink.elab", tmp_path / "t.txt", "10ms") == 2
    assert "unknown trace format (give a .csv or a .vcd file)" in capsys.readouterr().err
    assert run_interp(EXAMPLES / "blink.elab", tmp_path / "no" / "t.csv", "10ms") == 2
    assert "cannot write trace" in capsys.readouterr().err


def test_model_errors_and_missing_files(tmp_path, capsys):
    bad = tmp_path / "bad.elab"
    bad.write_text("model bad\nvar x: int16 = 70000\n")
    assert run_interp(bad, tmp_path / "t.csv", "10ms") == 1
    assert "bad.elab:2" in capsys.readouterr().err
    assert run_interp(tmp_path / "missing.elab", tmp_path / "t.csv", "10ms") == 1
    assert "no such file" in capsys.readouterr().err
    assert run_interp(EXAMPLES / "blink.elab", tmp_path / "t.csv", "10ms", tmp_path / "none.csv") == 2
    assert "cannot read stimulus" in capsys.readouterr().err


def test_real_time_and_pace(tmp_path):
    """Without --fast a run lasts its duration; paced runs are faster; the
    values are the same whatever the pace."""
    from easylab.cli import main

    traces = {}
    for label, args in (("real", []), ("pace", ["--pace", "4"]), ("fast", ["--fast"])):
        trace = tmp_path / f"{label}.csv"
        start = time.monotonic()
        assert main(["run", str(EXAMPLES / "blink.elab"), "--duration", "400ms", "--trace", str(trace), *args]) == 0
        traces[label] = (time.monotonic() - start, trace.read_bytes())
    assert traces["real"][0] >= 0.4
    assert traces["pace"][0] >= 0.1
    assert traces["real"][1] == traces["pace"][1] == traces["fast"][1]


def test_interface_errors_are_reported_before_anything_runs(tmp_path, capfd):
    """A model without a debug interface cannot serve --debug (status 1);
    a debug port that is taken is a usage error (status 2). Neither run
    leaves a trace file."""
    import socket

    trace = tmp_path / "i.csv"
    assert run_interp(MODEL, trace, "10ms", None, "--debug", f"pty:{tmp_path / 'dbg'}") == 1
    assert "has no debug interface" in capfd.readouterr().err
    assert not trace.exists() and not (tmp_path / "dbg").exists()
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        assert run_interp(EXAMPLES / "blink.elab", trace, "10ms", None, "--debug", f"tcp:{port}") == 2
    assert f"--debug tcp:{port}: cannot listen" in capfd.readouterr().err
    assert not trace.exists()
