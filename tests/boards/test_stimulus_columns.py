"""A stimulus column nothing reads is an error, as an unknown column is,
in every mode and on every board (boards/host/README.md, "Stimulus CSV";
the rule: generator/board/stimulus_columns.py): the host firmware, local
execution, remote execution and its host-board proxy, the AVR in simavr,
the PIC18 in gpsim and the F16 proxy's runner. Each names the column and
lists the columns that something reads, with a "did you mean" when one is
close; the two readers (C and Python) say the same for any header."""

from __future__ import annotations

import subprocess
import time
from pathlib import Path
from textwrap import dedent

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from easylab.board.stimulus_columns import edit_distance, suggestion
from easylab.interp import stimulus as py_stimulus
from easylab.pipeline import lower_file
from firmware_builds import build, cli, end_process, write_model

# `idle` is read by no task; `chip` runs the model's own handlers on the AVR,
# where the harness has no hardware behind it (the host simulates it).
MODEL = dedent("""\
    model stimcols "stimulus columns"
    import std
    device type Status(cs: string) {
        claims spi[0] cs cs
        out status: uint8
        driver "spi_status" impl avr "status.c"
    }
    device sensor: Pt100(channel = 0)
    device idle: AnalogIn(channel = 1)
    device chip: Status(cs = "PD7")
    device led: DigitalOut(pin = "PD2")
    param gain: int16 = 1000 range 500..2000
    var out: uint16
    var s: uint8
    dataflow D {
        avg = MovingAverage(n = 8)
        sq = SquareWave(half_period = 4)
        sensor.raw -> avg.x
        avg.y -> out
        chip.status -> s
        sq.y -> led.level
    }
    task main period 1 ms { run D }
    """)
STATUS_C = "EL_READ {\n    status = 7u;\n}\n"
# The boards without the model's handlers for `chip` (the PIC18, the F16 proxy): the same without it.
PLAIN = MODEL
for _line in ("device type Status(cs: string) {\n", "    claims spi[0] cs cs\n", "    out status: uint8\n",
              '    driver "spi_status" impl avr "status.c"\n', "}\n", 'device chip: Status(cs = "PD7")\n',
              "    chip.status -> s\n", 'device led: DigitalOut(pin = "PD2")\n',
              "    sq = SquareWave(half_period = 4)\n", "    sq.y -> led.level\n"):
    assert _line in PLAIN
    PLAIN = PLAIN.replace(_line, "", 1)

UNKNOWN = ("time_us,sensr.raw\n0,1\n", "unknown column 'sensr.raw' (did you mean 'sensor.raw'?)")
UNREAD = ("time_us,gain,idle.value\n0,600,1\n", "column 'idle.value': nothing reads it: no task reads device idle")
NO_HARDWARE = ("time_us,chip.status\n0,1\n", "column 'chip.status': nothing reads it: the simavr simulator has no "
               "hardware behind device chip (the model's handlers, driver spi_status)")
COLUMNS = "  valid columns: time_us, gain, out, s, sensor.raw"
COLUMNS_HOST = COLUMNS + ", chip.status"


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    folder = tmp_path_factory.mktemp("stimcols")
    for sub in ("full", "plain"):
        (folder / sub).mkdir()
    return (write_model(folder / "full", MODEL, {"status.c": STATUS_C}),
            write_model(folder / "plain", PLAIN))


@pytest.fixture(scope="module")
def host(models, tmp_path_factory):
    return build(models[0], "host", tmp_path_factory.mktemp("host")).executable


def _refused(proc: subprocess.CompletedProcess, csv: Path, message: str, columns: str) -> None:
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.splitlines()[:2] == [f"{csv}:1: {message}", columns], proc.stderr


def _csv(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "s.csv"
    path.write_text(text)
    return path


def _run(exe: Path, csv: Path, tmp_path: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(exe), "--fast", "--duration", "5ms", "--stimulus", str(csv), "--trace",
                           str(tmp_path / "t.csv")], capture_output=True, text=True, timeout=120,
                          stdin=subprocess.DEVNULL)


@pytest.mark.parametrize("case", [UNKNOWN, UNREAD], ids=["unknown", "unread"])
def test_host_firmware_and_local_execution_refuse_it_alike(host, models, tmp_path, case):
    csv = _csv(tmp_path, case[0])
    native = _run(host, csv, tmp_path)
    _refused(native, csv, case[1], COLUMNS_HOST)
    local = cli("run", models[0], "--fast", "--duration", "5ms", "--stimulus", csv, "--trace", tmp_path / "i.csv")
    _refused(local, csv, case[1], COLUMNS_HOST)
    assert local.stderr == native.stderr
    assert not (tmp_path / "t.csv").exists() and not (tmp_path / "i.csv").exists()


def test_the_host_simulates_a_device_the_avr_simulator_cannot_drive(host, models, tmp_path):
    csv = _csv(tmp_path, NO_HARDWARE[0])
    assert _run(host, csv, tmp_path).returncode == 0
    assert cli("run", models[0], "--fast", "--duration", "5ms", "--stimulus", csv).returncode == 0


@pytest.fixture(scope="module")
def avr(models, tmp_path_factory):
    return build(models[0], "avr", tmp_path_factory.mktemp("avr"), "--sim").simulator


@pytest.mark.parametrize("case", [UNKNOWN, UNREAD, NO_HARDWARE], ids=["unknown", "unread", "no hardware"])
def test_the_avr_simulator_refuses_it(avr, tmp_path, case):
    csv = _csv(tmp_path, case[0])
    _refused(_run(avr, csv, tmp_path), csv, case[1], COLUMNS)
    assert not (tmp_path / "t.csv").exists()


@pytest.mark.parametrize("board", ["pic18", "f16"])
@pytest.mark.parametrize("case", [UNKNOWN, UNREAD], ids=["unknown", "unread"])
def test_the_pic18_simulator_and_the_f16_runner_refuse_it(models, build_cache, tmp_path, case, board):
    exe = build_cache.get(("stimcols", board, str(models[1])),
                          lambda out: build(models[1], board, out, "--sim").simulator)
    csv = _csv(tmp_path, case[0])
    _refused(_run(exe, csv, tmp_path), csv, case[1], COLUMNS)


@pytest.mark.parametrize("case", [UNKNOWN, UNREAD], ids=["unknown", "unread"])
def test_remote_execution_and_its_host_board_proxy_refuse_it(models, tmp_path, case):
    from easylab.remote.proxy import build_proxy
    from easylab.remote.stimulus import device_columns

    program, result = lower_file(models[1])
    assert program is not None, result.report()
    proxy = build_proxy(program, "host", tmp_path / "proxy").executable
    csv = _csv(tmp_path, case[0])
    link = tmp_path / "link"
    # The proxy reads the device columns (cut as users cut them): it refuses them as the host board does.
    devices = tmp_path / "devices.csv"
    devices.write_text(device_columns(case[0], program) or case[0])
    proc = subprocess.run([str(proxy), "--link", f"pty:{link}", "--fast", "--stimulus", str(devices)],
                          capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    _refused(proc, devices, case[1], "  valid columns: time_us, sensor.raw")
    # `easylab remote` against a running proxy: refused before the run.
    served = subprocess.Popen([str(proxy), "--link", f"pty:{link}", "--fast"], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 10
        while not link.exists():
            assert served.poll() is None and time.monotonic() < deadline, "the proxy made no link"
            time.sleep(0.01)
        remote = cli("remote", models[1], "--target", link, "--fast", "--duration", "5ms", "--stimulus", csv,
                     "--trace", tmp_path / "r.csv", timeout=60)
    finally:
        end_process(served)
    _refused(remote, csv, case[1], COLUMNS)
    assert not (tmp_path / "r.csv").exists()


# ---- the two readers agree on any header ----

NAMES = ["gain", "out", "s", "sensor.raw", "idle.value", "chip.status", "led.level", "time_us", "sensor.raw[0]"]


@st.composite
def column_names(draw) -> str:
    """A column name: a valid one, or one a few edits (deletions,
    insertions, substitutions, swaps of neighbours) away from one."""
    name = list(draw(st.sampled_from(NAMES)))
    for _ in range(draw(st.integers(0, 4))):
        op = draw(st.sampled_from(["del", "ins", "sub", "swap"]))
        at = draw(st.integers(0, max(0, len(name) - 1)))
        char = draw(st.sampled_from(list("aeiorstu._[]0x")))
        if op == "del" and name:
            del name[at]
        elif op == "ins":
            name.insert(at, char)
        elif op == "sub" and name:
            name[at] = char
        elif op == "swap" and len(name) > 1:
            at = min(at, len(name) - 2)
            name[at], name[at + 1] = name[at + 1], name[at]
    return "".join(name)


@pytest.fixture(scope="module")
def both_readers(host, models, tmp_path_factory):
    """header -> (the host firmware's stderr, easylab run's reader's
    message): each "" when the header is accepted."""
    folder = tmp_path_factory.mktemp("agree")
    program, _ = lower_file(models[0])
    csv = folder / "s.csv"

    def read(header: str) -> tuple[str, str]:
        csv.write_text(header + "\n")
        proc = subprocess.run([str(host), "--fast", "--duration", "1ms", "--stimulus", str(csv)],
                              capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
        assert proc.returncode in (0, 2), proc.stderr
        try:
            py_stimulus.load(str(csv), program)
            py = ""
        except py_stimulus.StimulusError as err:
            py = f"{err}\n"
        return proc.stderr, py

    return read


@settings(max_examples=150, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(st.lists(column_names(), min_size=1, max_size=3))
def test_both_readers_say_the_same_of_any_header(both_readers, names):
    c, py = both_readers(",".join(["time_us", *names]))
    assert c == py


def test_a_close_name_is_suggested_and_a_far_one_is_not():
    assert edit_distance(b"gian", b"gain") == 1  # a swap of neighbours is one edit
    assert suggestion(b"sensr.raw", [b"gain", b"sensor.raw"]) == b"sensor.raw"
    assert suggestion(b"xyz", [b"gain", b"out"]) is None
    assert suggestion(b"x" * 65, [b"x" * 64]) is None  # longer than the C reader compares
