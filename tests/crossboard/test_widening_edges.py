"""Edges that widen between two actors (docs/language.md, "Widening"):
an edge's buffer holds its destination's type and the producer's tokens are
converted into it (docs/ir.md, "Buffers in C"). The model has a widening
edge alone and in fan-outs to inputs of several widths, with delays, and
between multirate actors (Upsample into Downsample and WindowStats); its
trace on the host board under each schedule, in local execution, on the
AVR in simavr and on the PIC18 in gpsim must be the same bytes."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from firmware_builds import build, cli, run_program

MODEL = Path(__file__).resolve().parent / "widen_edges.elab"
DURATION = "200ms"


def _trace(program: Path, out: Path) -> str:
    run_program(program, "--fast", "--duration", DURATION, "--trace", out)
    return out.read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def host_trace(tmp_path_factory) -> str:
    out = tmp_path_factory.mktemp("widen-host")
    return _trace(build(MODEL, "host", out / "build").executable, out / "trace.csv")


def test_widening_values_on_the_host(host_trace):
    """The values themselves: a negative int16 read as int32 stays negative
    (-4 is not 65532), the delays' tokens come first."""
    rows = [line.split(",") for line in host_trace.splitlines()]
    head, first = rows[0], dict(zip(rows[0], rows[2]))
    assert head[:3] == ["time_us", "sum32", "sum16"]
    # g.y -> a32.a delay [-4, 5]: the first firing adds -4 to r8's -3
    assert first["sum32"] == "-7"
    # r16 -> w32.b (-1000) and u8 -> d16 delay [-9, 9]: the first Downsample
    # gives the last of [-9, 9], then r8's -3, -3 ...
    assert first["wide"] == str(-1000 + 9)
    assert dict(zip(head, rows[3]))["wide"] == str(-2000 - 3)
    # up.y (int16) -> st.x (float32) and down.x (int32) delay [-1, -2, -3]
    assert first["hi"] == "-3" and first["held"] == "-3"
    # ru16 + ru8 into uint32 with a token of 65535 first
    assert first["u32"] == str(65535 + 7)


@pytest.mark.parametrize("schedule", ["flat", "min-buffer"])
def test_every_schedule_gives_the_same_trace(tmp_path, host_trace, schedule):
    """Circular buffers (schedules that are not single-appearance) convert
    the same way as linear ones."""
    exe = build(MODEL, "host", tmp_path / "build", "--schedule", schedule).executable
    assert _trace(exe, tmp_path / "trace.csv") == host_trace


def test_local_execution_gives_the_same_trace(tmp_path, host_trace):
    proc = cli("run", MODEL, "--fast", "--duration", DURATION, "--trace", tmp_path / "trace.csv")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert (tmp_path / "trace.csv").read_text(encoding="utf-8") == host_trace


def test_avr_and_pic18_simulators_give_the_same_trace(tmp_path, host_trace):
    boards = {"avr": ("--mcu", "atmega2560", "--sim"), "pic18": ("--mcu", "pic18f4620", "--sim")}
    with ThreadPoolExecutor(max_workers=2) as pool:
        built = {b: pool.submit(build, MODEL, b, tmp_path / b, *args) for b, args in boards.items()}
        for board, job in built.items():
            sim = job.result().simulator
            assert sim is not None and sim.is_file(), job.result().proc.stdout
            assert _trace(sim, tmp_path / f"{board}.csv") == host_trace, board
