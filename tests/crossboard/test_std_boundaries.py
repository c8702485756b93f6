"""Every std actor with its compile-time arguments at their ends, for every
type (boundaries.py generates the models: int8 .. uint32 and float32, each
at 0, its minimum and its maximum), builds on every board: a comparison
that an argument or a type decides (`Div<uint8>`'s `a < 0`, `Hysteresis`
with `off_below = 0` on an unsigned type or `on_above` at its maximum,
`Compare` at either end, `SquareWave(half_period = 0)`) is no error
(docs/language.md, "Actor code and compiler warnings"); and a user actor
whose parameter decides a comparison builds too. The host board and local
execution run the whole model to the same trace."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from boundaries import INTEGERS, NUMBERS, model
from easylab.core import types as T
from firmware_builds import build, cli, run_program

DURATION = "100ms"
SMALL = [T.INT8, T.UINT8, T.INT16, T.UINT16]
WIDE = [T.INT32, T.UINT32, T.FLOAT32]
# A user actor: its parameter and its type decide both comparisons.
USER = """
actor type Band<T: integer>(low: T, high: T) {
    in  x: T
    out y: bool
    step {{ y = (x >= low) && (x <= high) && (x >= 0); }}
}
"""


def write(folder: Path, name: str, text: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.elab"
    path.write_text(text, encoding="utf-8")
    return path


def user_model(name: str) -> str:
    """Band at the ends of every integer type, fed by a Ramp of the type."""
    lines = [f"model {name}", "import std", USER]
    body, k = [], 0
    for t in INTEGERS:
        body.append(f"    r_{t.name} = Ramp<{t.name}>(slope = {max(1, t.max // 8)})")
        for lo, hi in ((t.min, t.max), (0, 0), (t.max, t.min)):
            k += 1
            body += [f"    b{k} = Band<{t.name}>(low = ({lo}), high = ({hi}))", f"    r_{t.name}.y -> b{k}.x",
                     f"    b{k}.y -> o{k}"]
            lines.append(f"var o{k}: bool")
    lines += ["dataflow U {", *body, "}", "task main period 1 ms { run U }", ""]
    return "\n".join(lines)


# The actors whose C compares (or, as Select, met a 16-bit int's narrowing):
# what the MCU builds that cannot hold every actor keep.
COMPARING = {"Div", "Compare", "Hysteresis", "SquareWave", "MovingAverage", "Select", "Limit", "Counter"}


@pytest.fixture(scope="module")
def models(tmp_path_factory) -> dict[str, Path]:
    """The whole model (host, local execution); for the MCUs the same actors
    without a var per output ("mcu"), in halves of the types for the F16's
    C89 checks ("small", "wide"); the comparing actors in halves for the
    PIC18's RAM ("cmp_small", "cmp_wide") and per type for the 8051's 64 KB
    of code ("cmp_int8" ..); the user actor's model."""
    folder = tmp_path_factory.mktemp("ends")
    texts = {"all": model("ends_all", NUMBERS, big=True),
             "mcu": model("ends_mcu", NUMBERS, traced=False),
             "small": model("ends_small", SMALL, casts=False, others=False, traced=False),
             "wide": model("ends_wide", WIDE, traced=False),
             "cmp_small": model("ends_cmp_small", SMALL, casts=False, traced=False, only=COMPARING),
             "cmp_wide": model("ends_cmp_wide", WIDE, casts=False, others=False, traced=False, only=COMPARING),
             "user": user_model("ends_user")}
    for t in NUMBERS:
        texts[f"cmp_{t.name}"] = model(f"ends_cmp_{t.name}", [t], casts=False, others=t is T.INT8, traced=False,
                                       only=COMPARING)
    return {key: write(folder, f"ends_{key}", text) for key, text in texts.items()}


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


def test_avr_builds_them(tmp_path, models):
    with ThreadPoolExecutor(max_workers=2) as pool:
        jobs = [pool.submit(build, models[key], "avr", tmp_path / key, "--mcu", "atmega2560")
                for key in ("mcu", "user")]
        for job in jobs:
            job.result()


def test_f16_checks_and_its_proxy_build_them(tmp_path, models):
    """--check: gcc and clang in C89, clang-tidy with a 16-bit int, over
    every actor; --sim: the 16-bit proxy, sdcc -mmcs51, over the comparing
    actors of each type (the 8051's 64 KB of code holds one type's)."""
    jobs = [(key, "--check") for key in ("small", "wide", "user")]
    jobs += [(f"cmp_{t.name}", "--sim") for t in NUMBERS] + [("user", "--sim")]
    with ThreadPoolExecutor(max_workers=2) as pool:
        done = [pool.submit(build, models[key], "f16", tmp_path / f"{key}{mode}", mode) for key, mode in jobs]
        for job in done:
            job.result()


def test_pic18_builds_them(tmp_path, models):
    """sdcc's pic16 port over the comparing actors (every type, every end;
    sdcc's warning 94 comes from its front end, which the 8051 proxy's
    builds above run over each type too) and the user actor: the PIC18
    build writes actors into their dataflows' functions, above the pragma
    at the end of model.c, and must move it."""
    with ThreadPoolExecutor(max_workers=2) as pool:
        jobs = [pool.submit(build, models[key], "pic18", tmp_path / key, "--mcu", "pic18f4620")
                for key in ("cmp_small", "cmp_wide", "user")]
        for job in jobs:
            job.result()
