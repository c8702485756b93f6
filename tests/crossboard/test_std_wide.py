"""Std actors at the ends of their types' ranges (std_wide.elab): the
values the documentation promises, computed here exactly and saturated
(docs/stdlib.md), and the same trace bytes on the host board, in local
execution, on the AVR in simavr, on the PIC18 in gpsim and on the F16's
16-bit proxy in s51 (its wide arithmetic in two 32-bit words).

- MovingAverage<int32/uint32>: the mean of 2e9 and 2e9 is 2e9 (an int32
  running sum overflowed), truncated toward zero;
- Mul<uint32>: 4e9 * 3e9 saturates at UINT32_MAX (the 64-bit product
  overflowed to 0); Gain, Integrator, PID with gains at the int32 ends."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from firmware_builds import build, cli, run_program

MODEL = Path(__file__).resolve().parent / "std_wide.elab"
DURATION = "5ms"
I32 = (-(1 << 31), (1 << 31) - 1)
U32 = (0, (1 << 32) - 1)


def sat(v: int, bounds: tuple[int, int]) -> int:
    return max(bounds[0], min(bounds[1], v))


def tdiv(a: int, b: int) -> int:
    """C's division, truncating toward zero."""
    q = abs(a) // abs(b)
    return q if (a < 0) == (b < 0) else -q


def pid(setpoint: int, measured: int, kp: int, ki: int, kd: int, lo: int, hi: int, firings: int) -> list[int]:
    """std's PID as docs/stdlib.md describes it, in Python's integers."""
    integral = prev = 0
    out = []
    for _ in range(firings):
        error = setpoint - measured
        candidate = sat(integral + error * ki, I32)
        y = tdiv(error * kp + candidate + (error - prev) * kd, 1000)
        if y > hi:
            y = hi
            integral = candidate if error < 0 else integral
        elif y < lo:
            y = lo
            integral = candidate if error > 0 else integral
        else:
            integral = candidate
        prev = sat(error, I32)
        out.append(y)
    return out


def expected_rows() -> list[dict[str, int]]:
    """The values at 1, 2 and 3 ms."""
    lo32 = I32[0]
    down = [-1999999999, lo32, lo32]  # Ramp<int32>(slope = -1999999999), saturating
    s16 = [-32767, -32768, -32768]
    p1 = pid(U32[1], 3000000000, lo32, I32[1], I32[1], 0, U32[1], 3)
    p2 = pid(lo32, 2000000000, I32[1], lo32, lo32, lo32, I32[1], 3)
    rows = []
    for k in range(3):
        rows.append({
            "ma_i32": 2000000000, "ma_u32": 4000000000,
            "ma_ramp": tdiv(sum(down[max(0, k - 2):k + 1]), min(k + 1, 3)),
            "ma_i16": tdiv(sum(s16[:k + 1]), k + 1), "ma_u16": 65535,
            "mul_u32": sat(4000000000 * 3000000000, U32), "mul_i32": sat(2000000000 ** 2, I32),
            "mul_neg": sat(lo32 * 2000000000, I32),
            "gain_u32": sat(tdiv(U32[1] * I32[1], 1000), U32), "gain_i32": sat(tdiv(lo32 * lo32, 1000), I32),
            "integ_u32": U32[1], "integ_i32": I32[1],
            "diff_i32": sat(tdiv((down[k] - (down[k - 1] if k else 0)) * lo32, 1000), I32),
            "lp_u32": 0, "pid_u32": p1[k], "pid_i32": p2[k]})
    return rows


@pytest.fixture(scope="module")
def host_trace(tmp_path_factory) -> str:
    out = tmp_path_factory.mktemp("std-wide-host")
    exe = build(MODEL, "host", out / "build").executable
    run_program(exe, "--fast", "--duration", DURATION, "--trace", out / "trace.csv")
    return (out / "trace.csv").read_text(encoding="utf-8")


def test_the_values_are_exact_and_saturated(host_trace):
    lines = host_trace.splitlines()
    head = lines[0].split(",")
    got = [dict(zip(head, map(int, line.split(",")))) for line in lines[2:5]]
    for k, want in enumerate(expected_rows()):
        assert {name: got[k][name] for name in want} == want, f"at {k + 1} ms"


def test_local_execution_gives_the_same_trace(tmp_path, host_trace):
    proc = cli("run", MODEL, "--fast", "--duration", DURATION, "--trace", tmp_path / "trace.csv")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert (tmp_path / "trace.csv").read_text(encoding="utf-8") == host_trace


def test_every_simulated_board_gives_the_same_trace(tmp_path, host_trace):
    boards = {"avr": ("--mcu", "atmega2560", "--sim"), "pic18": ("--mcu", "pic18f4620", "--sim"),
              "f16": ("--sim",)}
    with ThreadPoolExecutor(max_workers=2) as pool:
        built = {b: pool.submit(build, MODEL, b, tmp_path / b, *args) for b, args in boards.items()}
        for board, job in built.items():
            sim = job.result().simulator
            assert sim is not None and sim.is_file(), job.result().proc.stdout
            run_program(sim, "--fast", "--duration", DURATION, "--trace", tmp_path / f"{board}.csv")
            assert (tmp_path / f"{board}.csv").read_text(encoding="utf-8") == host_trace, board
