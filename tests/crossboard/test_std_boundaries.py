"""Every std actor with its compile-time arguments at their ends, for every
type (boundaries.py generates the models: int8 .. uint32 and float32, each
at 0, its minimum and its maximum), builds on every board: a comparison
that an argument or a type decides (`Div<uint8>`'s `a < 0`, `Hysteresis`
with `off_below = 0` on an unsigned type or `on_above` at its maximum,
`Compare` at either end, `SquareWave(half_period = 0)`) is no error
(docs/language.md, "Actor code and compiler warnings"); and a user actor
whose parameter decides a comparison builds too. The host board and local
execution run the whole model to the same trace; the MCU boards' builds
are test_std_boundaries_mcu.py's."""

from __future__ import annotations

import pytest

from boundaries import INTEGERS
from firmware_builds import build, cli, run_program
from std_ends import models  # noqa: F401 (a fixture)

DURATION = "100ms"


@pytest.fixture(scope="module")
def host_traces(models, tmp_path_factory) -> dict[str, str]:
    out = tmp_path_factory.mktemp("ends-host")
    traces = {}
    for key in ("all", "user"):
        exe = build(models[key], "host", out / key).executable
        run_program(exe, "--fast", "--duration", DURATION, "--trace", out / f"{key}.csv")
        traces[key] = (out / f"{key}.csv").read_text(encoding="utf-8")
    return traces


def test_the_models_are_accepted(models):
    for path in models.values():
        proc = cli("check", path)
        assert proc.returncode == 0, proc.stdout + proc.stderr


def test_host_board_runs_them(host_traces):
    """The user actor's comparisons are C's: x >= 0 holds for an unsigned x."""
    rows = [line.split(",") for line in host_traces["user"].splitlines()]
    last = dict(zip(rows[0], rows[-1]))
    # per type: [min, max] holds for x >= 0; [0, 0] once the ramp moved on; [max, min] never
    for k, t in enumerate(INTEGERS):
        assert [last[f"o{3 * k + j}"] for j in (1, 2, 3)] == ["1", "0", "0"], t.name
    assert len(host_traces["all"].splitlines()) == 101


@pytest.mark.parametrize("key", ["all", "user"])
def test_local_execution_gives_the_host_trace(tmp_path, models, host_traces, key):
    proc = cli("run", models[key], "--fast", "--duration", DURATION, "--trace", tmp_path / "t.csv", timeout=900)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert (tmp_path / "t.csv").read_text(encoding="utf-8") == host_traces[key]


def test_host_board_builds_with_clang(tmp_path, models):
    for key in ("mcu", "user"):
        build(models[key], "host", tmp_path / key, "--cc", "clang")
