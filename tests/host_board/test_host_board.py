"""The host board (boards/host/): command line, time, stimulus, traces, nvram.

The board is built with a hand-written stand-in for a generated model and
the dispatcher (model.c in this folder), with gcc and clang under
-Werror, and with ASan/UBSan, then run as a process on real files.
"""

from __future__ import annotations

import csv
import os
import shutil
import signal
import struct
import subprocess
import time
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
BOARD = ROOT / "boards" / "host"
RUNTIME = ROOT / "runtime_c"

WARN = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-D_POSIX_C_SOURCE=200809L"]
SANITIZE = ["-g", "-O1", "-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer"]

HEADER = ("time_us,gain,limit,count,over,delta,level,elapsed,boots,neg,sensor.raw,sensor.ok,"
          "cam.px[0],cam.px[1],cam.px[2],cam.exposure,motor.speed,Cyl.active")
VALID_COLUMNS = ("valid columns: time_us, gain, limit, count, over, delta, level, elapsed, boots, neg, sensor.raw, "
                 "sensor.ok, cam.px (or cam.px[0] .. cam.px[2]), cam.exposure")


def _sources():
    """The firmware's board sources (board.toml; the folder also holds local
    execution's interfaces library files) and the fixture's model."""
    from easylab.board.registry import load_board

    return [str(BOARD / s) for s in load_board("host").description.sources] + [str(HERE / "model.c")]


def _build(out: Path, cc: str, flags: list[str]) -> Path:
    cmd = [cc, *WARN, *flags, f"-I{RUNTIME}", f"-I{BOARD}", *_sources(), "-lm", "-o", str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"{' '.join(cmd)}\n{proc.stdout}{proc.stderr}"
    assert proc.stderr == "", proc.stderr  # not even a warning
    return out


@pytest.fixture(scope="session")
def builds(tmp_path_factory):
    """name -> executable: asan (the default for tests), gcc, clang, tick250, wrap."""
    d = tmp_path_factory.mktemp("host_board_build")
    exes = {
        "asan": _build(d / "fixture_asan", "gcc", SANITIZE),
        "gcc": _build(d / "fixture_gcc", "gcc", ["-O2"]),
        "tick250": _build(d / "fixture_250", "gcc", SANITIZE + ["-DFIXTURE_TICK_US=250u"]),
        "wrap": _build(d / "fixture_wrap", "gcc", SANITIZE + ["-DFIXTURE_FIRST_TICK=4294967294u"]),
    }
    if shutil.which("clang"):
        exes["clang"] = _build(d / "fixture_clang", "clang", ["-O2"])
        exes["clang_asan"] = _build(d / "fixture_clang_asan", "clang", SANITIZE)
    return exes


@pytest.fixture
def exe(builds):
    return builds["asan"]


def run(exe, *args, cwd=None, env=None, timeout=60):
    full_env = dict(os.environ)
    full_env.update({"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1"})
    full_env.update(env or {})
    proc = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, cwd=cwd, env=full_env,
                          timeout=timeout)
    for marker in ("runtime error", "AddressSanitizer", "LeakSanitizer"):
        assert marker not in proc.stderr, proc.stderr
    return proc


def ok(exe, *args, **kw):
    proc = run(exe, *args, **kw)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    return proc


def fails(exe, *args, status=2, **kw):
    proc = run(exe, *args, **kw)
    assert proc.returncode == status, (proc.returncode, proc.stdout, proc.stderr)
    return proc.stderr


def report(proc):
    """The fixture's FIXTURE_REPORT lines as a dict."""
    return dict(line.split(": ", 1) for line in proc.stdout.splitlines())


STIMULUS = """time_us,sensor.raw,sensor.ok,cam.px,cam.exposure
0,50,1,1,0.1
1500,150,,,
3000,,0,2,
3000,-20,,,
7000,32767,true,,1e-3
"""

# By hand, from model.c and STIMULUS: tick 1 ms, a row only on change.
EXPECTED = HEADER + """
0,0.5,100,0,0,-50,3,0,1,0,50,1,1,1,1,0.100000001,25,Idle
2000,0.5,100,1,1,50,3,0,1,-1,150,1,1,1,1,0.100000001,75,Idle
3000,0.5,100,1,0,-120,6,0,1,-1,-20,0,2,2,2,0.100000001,-10,Extending
4000,0.5,100,2,0,-120,6,4,1,-2,-20,0,2,2,2,0.100000001,-10,Extending
5000,0.5,100,2,0,-120,6,4,1,-2,-20,0,2,2,2,0.100000001,-10,Extending+Holding
6000,0.5,100,3,0,-120,6,4,1,-3,-20,0,2,2,2,0.100000001,-10,Holding
7000,0.5,100,3,1,-101,6,4,1,-3,32767,1,2,2,2,0.00100000005,16383.5,Holding
8000,0.5,100,4,1,-101,6,8,1,-4,32767,1,2,2,2,0.00100000005,16383.5,Holding
9000,0.5,100,4,1,-101,6,8,1,-4,32767,1,2,2,2,0.00100000005,16383.5,
10000,0.5,100,5,1,-101,6,8,1,-5,32767,1,2,2,2,0.00100000005,16383.5,
12000,0.5,100,6,1,-101,6,12,1,-6,32767,1,2,2,2,0.00100000005,16383.5,Idle
"""


def rows(text):
    return [line.split(",") for line in text.splitlines()[1:]]


# ---------------------------------------------------------------- builds


def test_builds_warning_free_with_gcc_clang_and_sanitizers(builds):
    assert {"asan", "gcc", "tick250", "wrap"} <= set(builds)


@pytest.mark.parametrize("name", ["gcc", "clang", "clang_asan"])
def test_every_build_gives_the_same_trace(builds, tmp_path, name):
    if name not in builds:
        pytest.skip("clang not installed")
    (tmp_path / "s.csv").write_text(STIMULUS)
    ok(builds[name], "--fast", "--duration", "13ms", "--stimulus", tmp_path / "s.csv", "--trace", tmp_path / "t.csv")
    assert (tmp_path / "t.csv").read_text() == EXPECTED


# ---------------------------------------------------------------- command line


def test_help_lists_every_option(exe):
    out = ok(exe, "--help").stdout
    assert out.startswith("usage: fixture_asan [OPTION]...")
    for option in ("--fast", "--duration T", "--stimulus FILE.csv", "--trace FILE.csv|FILE.vcd", "--nvram FILE",
                   "--help"):
        assert f"  {option} " in out
    assert "fixture" in out and "0x12345678" in out


@pytest.mark.parametrize("args, message", [
    (["--bogus"], "fixture_asan: unknown option '--bogus' (try --help)"),
    (["--bogus=3"], "fixture_asan: unknown option '--bogus' (try --help)"),
    (["-f"], "fixture_asan: unexpected argument '-f' (try --help)"),
    (["model.csv"], "fixture_asan: unexpected argument 'model.csv' (try --help)"),
    (["--trace"], "fixture_asan: option --trace needs a value: --trace FILE.csv|FILE.vcd"),
    (["--fast=yes"], "fixture_asan: option --fast takes no value"),
    (["--fast", "--fast"], "fixture_asan: option --fast given more than once"),
    (["--duration", "1s", "--duration=2s"], "fixture_asan: option --duration given more than once"),
    (["--duration", "10"], "fixture_asan: --duration 10: a duration needs a unit: us, ms, s, m or h"),
    (["--duration", "10 parsecs"], "fixture_asan: --duration 10 parsecs: unknown time unit"),
    (["--duration", "fast"], "fixture_asan: --duration fast: not a duration"),
    (["--duration", "-1s"], "fixture_asan: --duration -1s: not a duration"),
    (["--duration", "1.0000005ms"], "fixture_asan: --duration 1.0000005ms: duration finer than 1 us"),
    (["--duration", "99999999999999999999s"], "fixture_asan: --duration 99999999999999999999s: duration too long"),
])
def test_bad_command_lines_exit_2_with_one_clear_line(exe, args, message):
    err = fails(exe, *args)
    assert err.startswith(message), err
    assert err.count("\n") == 1


@pytest.mark.parametrize("duration, ticks, last", [
    ("13ms", 13, "12"),
    ("--duration=13ms", 13, "12"),
    ("12001us", 13, "12"),
    ("12ms", 12, "11"),          # the instant at exactly the duration is not processed
    ("1.5ms", 2, "1"),
    ("0.0025s", 3, "2"),
    ("2500 us", 3, "2"),
    ("0s", 0, "-"),
    ("1us", 1, "0"),
])
def test_duration_ends_the_run_before_its_instant(exe, duration, ticks, last):
    args = [duration] if duration.startswith("--") else ["--duration", duration]
    rep = report(ok(exe, "--fast", *args, env={"FIXTURE_REPORT": "1"}))
    assert rep == {"ticks": str(ticks), "last": last}


def test_duration_units(builds):
    rep = report(ok(builds["gcc"], "--fast", "--duration", "1m", env={"FIXTURE_REPORT": "1"}))
    assert rep["ticks"] == "60000"
    rep = report(ok(builds["tick250"], "--fast", "--duration", "1ms", env={"FIXTURE_REPORT": "1"}))
    assert rep == {"ticks": "4", "last": "3"}
    rep = report(ok(builds["tick250"], "--fast", "--duration", "1001us", env={"FIXTURE_REPORT": "1"}))
    assert rep == {"ticks": "5", "last": "4"}


def test_last_trace_row_is_before_the_duration(exe, tmp_path):
    ok(exe, "--fast", "--duration", "9ms", "--trace", tmp_path / "t.csv")
    assert rows((tmp_path / "t.csv").read_text())[-1][0] == "8000"
    ok(exe, "--fast", "--duration", "10ms", "--trace", tmp_path / "t.csv")
    assert rows((tmp_path / "t.csv").read_text())[-1][0] == "9000"


def test_tick_counter_wrap_is_extended_to_64_bits(builds, tmp_path):
    """The dispatcher's 32-bit ticks wrap; the board's logical time does not."""
    proc = ok(builds["wrap"], "--fast", "--duration", "4294967300ms", "--trace", tmp_path / "t.csv",
              env={"FIXTURE_REPORT": "1"})
    assert report(proc) == {"ticks": "6", "last": "4294967299"}
    times = [r[0] for r in rows((tmp_path / "t.csv").read_text())]
    assert times == ["4294967294000", "4294967295000", "4294967296000", "4294967297000", "4294967298000"]


# ---------------------------------------------------------------- real time and signals


def test_real_time_run_takes_its_duration(builds, tmp_path):
    start = time.monotonic()
    ok(builds["gcc"], "--duration", "200ms", "--trace", tmp_path / "rt.csv")
    elapsed = time.monotonic() - start
    assert 0.19 <= elapsed < 3.0, elapsed
    ok(builds["gcc"], "--fast", "--duration", "200ms", "--trace", tmp_path / "fast.csv")
    assert (tmp_path / "rt.csv").read_text() == (tmp_path / "fast.csv").read_text()


def test_fast_runs_are_deterministic(exe, tmp_path):
    for name in ("a", "b"):
        ok(exe, "--fast", "--duration", "50ms", "--trace", tmp_path / f"{name}.vcd")
    assert (tmp_path / "a.vcd").read_bytes() == (tmp_path / "b.vcd").read_bytes()


def wait_for_file(path, timeout=10.0):
    """The board creates the trace in el_port_init, after its signal handlers are set."""
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.01)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_signal_ends_the_run_cleanly_and_flushes_the_trace(builds, tmp_path, sig):
    trace = tmp_path / "sig.csv"
    proc = subprocess.Popen([str(builds["gcc"]), "--trace", str(trace)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    wait_for_file(trace)
    time.sleep(0.4)
    assert proc.poll() is None, "an endless run ended by itself"
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=10)
    assert proc.returncode == 0 and err == "", (proc.returncode, err)
    text = trace.read_text()
    assert text.endswith("\n")
    got = rows(text)
    last = int(got[-1][0])
    assert 50_000 <= last <= 10_000_000  # about 0.4 s of 1 ms ticks
    ok(builds["gcc"], "--fast", "--duration", "10s", "--trace", tmp_path / "ref.csv")
    ref = [r for r in rows((tmp_path / "ref.csv").read_text()) if int(r[0]) <= last]
    assert got == ref


def test_signal_closes_a_vcd_trace(builds, tmp_path):
    trace = tmp_path / "sig.vcd"
    proc = subprocess.Popen([str(builds["gcc"]), "--trace", str(trace)], stderr=subprocess.PIPE, text=True)
    wait_for_file(trace)
    time.sleep(0.3)
    proc.terminate()
    _, err = proc.communicate(timeout=10)
    assert proc.returncode == 0 and err == ""
    vcd = parse_vcd(trace.read_text())
    assert vcd["end"] > max(t for t, _ in vcd["changes"])


# ---------------------------------------------------------------- stimulus


def test_stimulus_applies_as_a_step_function(exe, tmp_path):
    (tmp_path / "s.csv").write_text(STIMULUS)
    ok(exe, "--fast", "--duration", "13ms", "--stimulus", tmp_path / "s.csv", "--trace", tmp_path / "t.csv")
    assert (tmp_path / "t.csv").read_text() == EXPECTED


def test_stimulus_between_ticks_applies_at_the_next_tick(builds, tmp_path):
    (tmp_path / "s.csv").write_text("time_us,sensor.raw\n0,1\n1100,2\n1250,3\n")
    ok(builds["tick250"], "--fast", "--duration", "2ms", "--stimulus", tmp_path / "s.csv",
       "--trace", tmp_path / "t.csv")
    raw = HEADER.split(",").index("sensor.raw")
    got = {r[0]: r[raw] for r in rows((tmp_path / "t.csv").read_text())}
    assert got["0"] == "1"
    assert got["1250"] == "3"  # 1100 applies at 1250 and is overridden by the row at 1250 at once
    assert "1000" not in got or got["1000"] == "1"


def test_stimulus_is_applied_only_when_the_device_is_read(exe, tmp_path):
    (tmp_path / "s.csv").write_text("time_us,sensor.raw,cam.px\n0,1,1\n3000,2,2\n")
    ok(exe, "--fast", "--duration", "6ms", "--stimulus", tmp_path / "s.csv", "--trace", tmp_path / "t.csv",
       env={"FIXTURE_CAM_EVERY": "2"})
    cols = HEADER.split(",")
    got = {r[0]: (r[cols.index("sensor.raw")], r[cols.index("cam.px[1]")]) for r in rows((tmp_path / "t.csv").read_text())}
    assert got["3000"] == ("2", "1")   # the cam is not read at tick 3
    assert got["4000"] == ("2", "2")


def test_stimulus_element_columns_and_held_data(exe, tmp_path):
    (tmp_path / "s.csv").write_text("time_us,cam.px[2],cam.px[0]\n0,7,200\n2000,,255\n")
    ok(exe, "--fast", "--duration", "3ms", "--stimulus", tmp_path / "s.csv", "--trace", tmp_path / "t.csv")
    cols = HEADER.split(",")
    got = [(r[0], r[cols.index("cam.px[0]")], r[cols.index("cam.px[1]")], r[cols.index("cam.px[2]")],
            r[cols.index("sensor.raw")], r[cols.index("level")]) for r in rows((tmp_path / "t.csv").read_text())]
    assert got == [("0", "200", "0", "7", "0", "207"), ("2000", "255", "0", "7", "0", "262")]


def test_stimulus_format_tolerances(exe, tmp_path):
    """CRLF, a byte-order mark, spaces around cells, blank lines, bool words, inf."""
    (tmp_path / "s.csv").write_bytes(b"\xef\xbb\xbftime_us , sensor.ok,cam.exposure\r\n\r\n 0 , false , -inf\r\n"
                                     b"1000,true,3.40282347e+38\r\n")
    ok(exe, "--fast", "--duration", "2ms", "--stimulus", tmp_path / "s.csv", "--trace", tmp_path / "t.csv")
    cols = HEADER.split(",")
    got = [(r[0], r[cols.index("sensor.ok")], r[cols.index("cam.exposure")]) for r in rows((tmp_path / "t.csv").read_text())]
    assert got == [("0", "0", "-inf"), ("1000", "1", "3.40282347e+38")]


def test_header_only_stimulus_changes_nothing(exe, tmp_path):
    (tmp_path / "s.csv").write_text("time_us,sensor.raw\n")
    ok(exe, "--fast", "--duration", "3ms", "--stimulus", tmp_path / "s.csv", "--trace", tmp_path / "a.csv")
    ok(exe, "--fast", "--duration", "3ms", "--trace", tmp_path / "b.csv")
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()


LONG = "x" * 70000

STIMULUS_ERRORS = [
    ("time_us,sensor.rew\n", 1, "unknown column 'sensor.rew'", True),
    ("time_us,sensor.raw,\n", 1, "empty column name", True),
    ("time_us,motor.speed\n", 1, "column 'motor.speed': motor.speed is a device `in` datum", True),
    ("time_us,cam.px[3]\n", 1, "column 'cam.px[3]': cam.px has 3 elements", True),
    ("time_us,sensor.raw[0]\n", 1, "column 'sensor.raw[0]': sensor.raw has 1 element (no index)", True),
    ("time_us,cam.px[x]\n", 1, "unknown column 'cam.px[x]'", True),
    ("time_us,cam.px,cam.px[1]\n", 1, "columns 'cam.px' and 'cam.px[1]' set the same datum", False),
    ("time_us,sensor.ok,sensor.ok\n", 1, "columns 'sensor.ok' and 'sensor.ok' set the same datum", False),
    ("time,sensor.raw\n", 1, "the first column must be time_us, not 'time'", False),
    ("", 1, "empty file: the first line must be the header time_us,DATUM,...", False),
    ("\n\n", 1, "empty file", False),
    ("time_us,sensor.raw\n0,1\n0,1,2\n", 3, "3 cells, expected 2 as in the header", False),
    ("time_us,sensor.raw,sensor.ok\n0,1\n", 2, "2 cells, expected 3 as in the header", False),
    ("time_us,sensor.raw\n0,abc\n", 2, "bad number 'abc' for column 'sensor.raw' (int16: a decimal integer)", False),
    ("time_us,sensor.raw\n0,0x10\n", 2, "bad number '0x10' for column 'sensor.raw'", False),
    ("time_us,sensor.raw\n0,1.5\n", 2, "bad number '1.5' for column 'sensor.raw'", False),
    ("time_us,sensor.raw\n0,32768\n", 2, "value 32768 out of range for column 'sensor.raw' (int16: -32768 .. 32767)",
     False),
    ("time_us,sensor.raw\n0,-32769\n", 2, "value -32769 out of range for column 'sensor.raw' (int16", False),
    ("time_us,cam.px\n0,256\n", 2, "value 256 out of range for column 'cam.px' (uint8: 0 .. 255)", False),
    ("time_us,cam.px[1]\n0,-1\n", 2, "value -1 out of range for column 'cam.px[1]' (uint8: 0 .. 255)", False),
    ("time_us,cam.px\n0,99999999999999999999999\n", 2, "value 99999999999999999999999 out of range", False),
    ("time_us,sensor.ok\n0,2\n", 2, "bad value '2' for column 'sensor.ok' (bool: 0, 1, true or false)", False),
    ("time_us,cam.exposure\n0,1e39\n", 2, "value '1e39' out of range for column 'cam.exposure' (float32", False),
    ("time_us,cam.exposure\n0,1.5x\n", 2, "bad number '1.5x' for column 'cam.exposure' (float32)", False),
    ("time_us,sensor.raw\n0,1\n2000,2\n1999,3\n", 4,
     "time 1999 is before the previous row's time 2000 (times must not decrease)", False),
    ("time_us,sensor.raw\n-5,1\n", 2, "bad time '-5' (time_us: whole microseconds, 0 or more)", False),
    ("time_us,sensor.raw\n1.5,1\n", 2, "bad time '1.5'", False),
    ("time_us,sensor.raw\n,1\n", 2, "bad time ''", False),
    ("time_us,sensor.raw\n0,1\n" + LONG + "\n", 3, "line longer than 65536 bytes", False),
    ("time_us," + LONG + "\n", 1, "line longer than 65536 bytes", False),
    ("time_us,sensor.raw\n0,\x001\n", 2, "NUL byte in line", False),
]


def test_stimulus_writes_params_and_vars_once_at_their_time(exe, tmp_path):
    # A param's value is written at the first instant at or after its time
    # (like an interface write) and then holds until something writes it.
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,gain,sensor.raw\n0,,10\n2500,3.5,\n")
    trace = tmp_path / "t.csv"
    run(exe, "--fast", "--duration", "5ms", "--stimulus", stim, "--trace", trace)
    rows = list(csv.DictReader(trace.open()))
    gain = {int(r["time_us"]): r["gain"] for r in rows}
    assert all(g != "3.5" for t, g in gain.items() if t < 3000), gain
    assert gain[3000] == "3.5" and rows[-1]["gain"] == "3.5", gain


@pytest.mark.parametrize("content, line, message, lists_columns", STIMULUS_ERRORS)
def test_stimulus_errors_are_reported_before_the_run(exe, tmp_path, content, line, message, lists_columns):
    stim = tmp_path / "bad.csv"
    stim.write_text(content)
    trace = tmp_path / "t.csv"
    err = fails(exe, "--fast", "--stimulus", stim, "--trace", trace, "--nvram", tmp_path / "nv")
    first, *rest = err.splitlines()
    assert first.startswith(f"{stim}:{line}: {message}"), err
    if lists_columns:
        assert rest == [f"  {VALID_COLUMNS}"]
    else:
        assert rest == []
    assert not trace.exists()  # nothing ran
    assert not (tmp_path / "nv").exists()


def test_missing_stimulus_file(exe, tmp_path):
    err = fails(exe, "--stimulus", tmp_path / "none.csv")
    assert err == f"fixture_asan: cannot read stimulus {tmp_path / 'none.csv'}: No such file or directory\n"


# ---------------------------------------------------------------- traces


def test_trace_format_errors(exe, tmp_path):
    err = fails(exe, "--trace", tmp_path / "t.txt")
    assert err == f"fixture_asan: --trace {tmp_path / 't.txt'}: unknown trace format (give a .csv or a .vcd file)\n"
    for name in ("t.csv", "t.vcd"):
        path = tmp_path / "no" / "such" / name
        err = fails(exe, "--fast", "--trace", path)
        assert err == f"fixture_asan: cannot write trace {path}: No such file or directory\n"
    ok(exe, "--fast", "--duration", "1ms", "--trace", tmp_path / "UPPER.CSV")
    assert (tmp_path / "UPPER.CSV").read_text().startswith("time_us,")


def test_trace_write_error_gives_status_1(exe):
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    link = Path("/tmp") / f"el_host_full_{os.getpid()}.csv"
    link.unlink(missing_ok=True)
    link.symlink_to("/dev/full")
    try:
        err = fails(exe, "--fast", "--duration", "100ms", "--trace", link, status=1)
    finally:
        link.unlink()
    assert err == f"fixture_asan: error writing trace {link}: No space left on device\n"


def test_csv_rows_only_on_change(exe, tmp_path):
    ok(exe, "--fast", "--duration", "100ms", "--trace", tmp_path / "t.csv")
    got = rows((tmp_path / "t.csv").read_text())
    assert got[0][0] == "0"
    for a, b in zip(got, got[1:]):
        assert int(a[0]) < int(b[0]) and a[1:] != b[1:]


def parse_vcd(text):
    """Declarations, and the value changes as (time, {id: value}) with the end time."""
    head, body = text.split("$enddefinitions $end\n")
    decls = {}
    scopes = []
    for line in head.splitlines():
        tok = line.split()
        if tok[0] == "$scope":
            assert tok[1] == "module" and tok[-1] == "$end"
            scopes.append(tok[2])
        elif tok[0] == "$var":
            assert len(tok) == 6 and tok[-1] == "$end", line
            decls[tok[3]] = (tok[1], int(tok[2]), tok[4])
        else:
            assert tok[0] in ("$comment", "$timescale", "$upscope"), line
    assert "$timescale 1us $end" in head
    changes = []
    lines = body.splitlines()
    assert lines[1] == "$dumpvars"
    end = None
    cur = None
    for line in lines:
        if line.startswith("#"):
            cur = {}
            changes.append((int(line[1:]), cur))
        elif line in ("$dumpvars", "$end"):
            continue
        elif line[0] in "br":
            value, ident = line[1:].split(" ")
            assert ident not in cur
            cur[ident] = line[0] + value
        else:
            assert line[0] in "01" and len(line) >= 2
            cur[line[1:]] = line[0]
    # the last time line only marks the end
    end, last = changes.pop()
    assert last == {}
    return {"scopes": scopes, "decls": decls, "changes": changes, "end": end}


SIGNED = {"limit", "delta", "neg", "sensor.raw"}


def vcd_to_csv_value(name, kind, width, value):
    if kind == "real":
        assert value.startswith("r")
        return value[1:]
    if name == "Cyl.active":
        bits = value[1:] if value.startswith("b") else value
        assert len(bits) == width
        steps = ["Idle", "Extending", "Holding"]
        return "+".join(s for i, s in enumerate(steps) if bits[width - 1 - i] == "1")
    if width == 1:
        return value
    assert value.startswith("b") and len(value) == width + 1
    n = int(value[1:], 2)
    if name in SIGNED and n >= 1 << (width - 1):
        n -= 1 << width
    return str(n)


def test_vcd_matches_the_csv_trace(exe, tmp_path):
    (tmp_path / "s.csv").write_text(STIMULUS)
    for ext in ("csv", "vcd"):
        ok(exe, "--fast", "--duration", "13ms", "--stimulus", tmp_path / "s.csv", "--trace", tmp_path / f"t.{ext}")
    text = (tmp_path / "t.vcd").read_text()
    vcd = parse_vcd(text)
    assert vcd["scopes"] == ["fixture"]
    assert text.startswith("$comment EasyLab trace of model fixture, program id 0x12345678, tick 1000 us $end\n"
                           "$timescale 1us $end\n$scope module fixture $end\n")
    kinds = {name: (kind, width) for kind, width, name in vcd["decls"].values()}
    assert kinds == {
        "gain": ("real", 64), "limit": ("wire", 16), "count": ("wire", 32), "over": ("wire", 1),
        "delta": ("wire", 8), "level": ("wire", 16), "elapsed": ("wire", 32), "boots": ("wire", 32),
        "neg": ("wire", 32), "sensor.raw": ("wire", 16), "sensor.ok": ("wire", 1), "cam.px(0)": ("wire", 8),
        "cam.px(1)": ("wire", 8), "cam.px(2)": ("wire", 8), "cam.exposure": ("real", 64),
        "motor.speed": ("real", 64), "Cyl.active": ("wire", 3),
    }
    # Every signal in $dumpvars, then only changes, at the CSV's row times.
    csv_rows = rows(EXPECTED)
    names = HEADER.split(",")[1:]
    by_name = {name: ident for ident, (_, _, name) in vcd["decls"].items()}
    assert [t for t, _ in vcd["changes"]] == [int(r[0]) for r in csv_rows]
    assert set(vcd["changes"][0][1]) == set(vcd["decls"])
    state = {}
    for (t, changed), row in zip(vcd["changes"], csv_rows):
        for ident, value in changed.items():
            assert state.get(ident) != value, f"unchanged value written at {t}"
            state[ident] = value
        for name, expected in zip(names, row[1:]):
            vname = name.replace("[", "(").replace("]", ")")
            kind, width, _ = vcd["decls"][by_name[vname]]
            assert vcd_to_csv_value(name, kind, width, state[by_name[vname]]) == expected, (t, name)
    assert vcd["end"] == 13000
    # Signed values in two's complement: neg = -6 at the end.
    assert state[by_name["neg"]] == "b" + format((1 << 32) - 6, "032b")
    assert state[by_name["Cyl.active"]] == "b001"


# ---------------------------------------------------------------- nvram


def test_nvram_persists_across_runs(exe, tmp_path):
    nv = tmp_path / "nv.bin"
    for boots in (1, 2, 3):
        ok(exe, "--fast", "--duration", "1ms", "--nvram", nv, "--trace", tmp_path / "t.csv")
        row = rows((tmp_path / "t.csv").read_text())[0]
        assert row[HEADER.split(",").index("boots")] == str(boots)
        data = nv.read_bytes()
        assert len(data) == 4096
        assert data[:4] == struct.pack("<I", boots) and data[4:] == b"\xff" * 4092
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nv.bin", "t.csv"]  # no temporary left


def test_without_nvram_the_store_is_in_memory(exe, tmp_path):
    for _ in range(2):
        ok(exe, "--fast", "--duration", "1ms", "--trace", tmp_path / "t.csv")
        assert rows((tmp_path / "t.csv").read_text())[0][HEADER.split(",").index("boots")] == "1"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csv"]


def test_nvram_errors(exe, tmp_path):
    wrong = tmp_path / "wrong.bin"
    wrong.write_bytes(b"\0" * 100)
    err = fails(exe, "--nvram", wrong)
    assert err == f"fixture_asan: nvram {wrong}: 100 bytes, expected 4096 (delete it to start erased)\n"
    missing_dir = tmp_path / "no" / "nv.bin"
    err = fails(exe, "--nvram", missing_dir)
    assert err == f"fixture_asan: cannot create nvram {missing_dir}: No such file or directory\n"
    err = fails(exe, "--nvram", tmp_path)
    assert err.startswith(f"fixture_asan: cannot open nvram {tmp_path}: ")
    err = fails(exe, "--nvram=")
    assert err == "fixture_asan: --nvram needs a file name\n"


def test_nvram_reads_an_existing_file(exe, tmp_path):
    nv = tmp_path / "nv.bin"
    nv.write_bytes(struct.pack("<I", 41) + b"\x00" * 4092)
    ok(exe, "--fast", "--duration", "1ms", "--nvram", nv, "--trace", tmp_path / "t.csv")
    assert rows((tmp_path / "t.csv").read_text())[0][HEADER.split(",").index("boots")] == "42"
    assert nv.read_bytes() == struct.pack("<I", 42) + b"\x00" * 4092


# ---------------------------------------------------------------- shutdown


def test_overruns_are_summarised_on_one_line(exe):
    proc = run(exe, "--fast", "--duration", "1ms", env={"FIXTURE_OVERRUNS": "3"})
    assert proc.returncode == 0
    assert proc.stderr == "fixture_asan: overruns: logger 3\n"
    assert ok(exe, "--fast", "--duration", "1ms").stdout == ""


@pytest.mark.parametrize("length, crlf, message", [
    (65536, False, "unknown column"),
    (65536, True, "unknown column"),
    (65537, False, "line longer than 65536 bytes"),
])
def test_line_length_limit_is_exact(exe, tmp_path, length, crlf, message):
    header = "time_us," + "y" * (length - len("time_us,"))
    (tmp_path / "s.csv").write_bytes(header.encode() + (b"\r\n" if crlf else b"\n"))
    err = fails(exe, "--stimulus", tmp_path / "s.csv")
    assert err.startswith(f"{tmp_path / 's.csv'}:1: {message}")
