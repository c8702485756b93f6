"""Stretches of instants in the runner alone (no trace, virtual time: the
runner goes from instant to instant without Python) give the host-native
firmware's values.

A run without a trace is cut into random numbers of instants; after each
piece the published items and the charts' activity, written as the host
board writes a trace row, must be the firmware's trace at that instant.
Stimuli end stretches where they write (their device data, params and
vars), charts need Python at their task's instants, a live replacement
and the publications it carries end them too.
"""

from __future__ import annotations

import csv
import io
import random
from bisect import bisect_right
from pathlib import Path

import pytest

from easylab.interp import Engine, PluginCache
from easylab.interp.stimulus import load as load_stimulus
from easylab.interp.trace import Sampler, TraceWriter, columns_of
from interp_testlib import DATA, lower, run_host, run_interp
from test_interp_equivalence import CASES as EQUIVALENCE_CASES

# The equivalence tests' models, and edges that widen (into vars, from a
# param, into ports of two types from one output, through a channel).
CASES = {**EQUIVALENCE_CASES, "widen": (DATA / "widen.elab", None, "1s")}
from test_interp_live import EDITED, LIVE, write_model



def pieces(rng: random.Random, ticks: int):
    """Instants per piece: a few, or a 40th or a 10th of the run's ticks."""
    while True:
        yield rng.choice((1, 2, 3, 7, max(1, ticks // 40), max(1, ticks // 10)))


def _table(trace: Path) -> tuple[list[int], list[list[str]]]:
    """A CSV trace as sorted times and their rows (cells after time_us)."""
    lines = list(csv.reader(io.StringIO(trace.read_text())))[1:]
    return [int(r[0]) for r in lines], [r[1:] for r in lines]


def _at(table, t: int) -> list[str]:
    """The row in force at time t (a row holds until the next one)."""
    times, cells = table
    return cells[bisect_right(times, t) - 1]


class PieceRecorder:
    """Runs an engine piece by piece and writes a trace row after each piece
    (the host board's CSV, through the interpreter's TraceWriter)."""

    def __init__(self, engine: Engine, path: Path):
        self.engine = engine
        self.path = path
        program = engine.program
        self.sampler = Sampler(columns_of(program))
        self.sampler.bind(program, engine.state.published, engine.state.charts)
        self.writer = TraceWriter(str(path), program, self.sampler.columns)
        self.ends: list[int] = []

    def piece(self, duration_us: int, instants: int, rebind: bool = False) -> bool:
        """Run at most ``instants`` instants (``rebind``: the columns read
        the program swapped in meanwhile); False once the duration is over."""
        before = self.engine.last_time_us
        self.engine.run(duration_us, instants=instants)
        if self.engine.last_time_us == before:
            return False
        if rebind:
            self.sampler.bind(self.engine.program, self.engine.state.published, self.engine.state.charts)
        self.ends.append(self.engine.last_time_us)
        self.writer.record(self.engine.last_time_us, self.sampler.snapshot())
        return True

    def close(self):
        self.engine.shutdown()
        self.writer.close()
        return _table(self.path)


@pytest.fixture(scope="module")
def firmware(host_firmware):
    host_firmware.prebuild(model for model, _, _ in CASES.values())
    return host_firmware


def test_widening_edges_as_the_firmware(firmware, tmp_path):
    """Traced (the engine's step for every instant), as for the other models
    in test_interp_equivalence.py."""
    model, _, duration = CASES["widen"]
    host, interp = tmp_path / "host.csv", tmp_path / "interp.csv"
    run_host(firmware(model), host, duration)
    assert run_interp(model, interp, duration) == 0
    assert interp.read_bytes() == host.read_bytes()
    assert ",-128," in host.read_text() and ",255," in host.read_text()  # sign and zero extension


def _duration_us(text: str) -> int:
    return int(text[:-2]) * 1000 if text.endswith("ms") else int(text[:-1]) * 1_000_000


@pytest.mark.parametrize("name", list(CASES))
def test_stretches_give_the_firmware_values(name, firmware, tmp_path):
    model, stimulus, duration = CASES[name]
    host = tmp_path / "host.csv"
    run_host(firmware(model), host, duration, stimulus)
    expected = _table(host)
    program = lower(model)
    engine = Engine(program, PluginCache(), load_stimulus(str(stimulus), program) if stimulus else None)
    recorder = PieceRecorder(engine, tmp_path / "pieces.csv")
    ticks = _duration_us(duration) // program.tick_us
    for count in pieces(random.Random(name), ticks):
        if not recorder.piece(_duration_us(duration), count):
            break
    got = recorder.close()
    assert len(recorder.ends) > 10
    for t in recorder.ends:
        assert _at(got, t) == _at(expected, t), t
    if all(plan.native for plan in engine.state.instants):  # no chart (which needs Python at its task's instants)
        assert engine.native_instants > ticks // 4  # stretches end where the stimulus writes


def _without_chart(text: str) -> str:
    """tests/interp/data/live.elab with its task running the dataflow itself."""
    start, end = text.index("chart Mode {"), text.index("task filter")
    return text[:start] + text[end:].replace("{ run Mode }", "{ run Filter }")


def test_no_stretch_over_a_replacement(tmp_path):
    """A replacement swaps in at the next instant after the pieces before it
    ran in the runner alone, and the activation it carries is published at
    its deadline: the same rows as the traced run of the same swap."""
    live = lower(write_model(tmp_path / "live.elab", _without_chart(LIVE)))
    edited = lower(write_model(tmp_path / "edited.elab", _without_chart(EDITED)))

    stimulus = tmp_path / "sparse.csv"  # a value every 130 ms: stretches in between
    stimulus.write_text("time_us,sensor.value\n" + "".join(f"{k * 130_000},{(k * 97) % 400 - 50}\n"
                                                          for k in range(16)))

    def run(trace: Path | None) -> Engine:
        writer = TraceWriter(str(trace), live, columns_of(live)) if trace else None
        engine = Engine(live, PluginCache(), load_stimulus(str(stimulus), live), writer)
        engine.run(instants=58)
        engine.replace_model(edited)
        return engine

    traced = run(tmp_path / "traced.csv")
    traced.run(2_000_000)
    traced.shutdown()
    expected = _table(tmp_path / "traced.csv")

    recorder = PieceRecorder(run(None), tmp_path / "pieces.csv")
    assert recorder.piece(2_000_000, 1, rebind=True)  # the swap
    for count in pieces(random.Random(7), 200):
        if not recorder.piece(2_000_000, count):
            break
    engine = recorder.engine
    got = recorder.close()
    assert engine.activations == traced.activations == {"filter": 200, "slow": 67}
    assert engine.native_instants > 100
    for t in recorder.ends:
        assert _at(got, t) == _at(expected, t), t
