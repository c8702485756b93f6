"""The camera line-following example (examples/vision_line/): it checks,
is canonically laid out, is planned on two cores from its declared costs
with a predicted speedup of at least 1.7, and its trace is the same on 1, 2
and 4 cores on the host board and in local execution, for its stimulus and
for random ones; the line it finds is the line its camera draws."""

from __future__ import annotations

import json
import random
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from multicore_testlib import build_cores, cli, run
from test_multicore_local import _local_trace

FOLDER = Path(__file__).resolve().parents[2] / "examples" / "vision_line"
MODEL = FOLDER / "vision_line.elab"
STIMULUS = FOLDER / "vision_line.stimulus.csv"
CORES = (1, 2, 4)
DURATION = "40ms"  # 40 frames: the camera's gap (frames 20 to 29) and the stimulus's change of gain


@pytest.fixture(scope="module")
def programs(tmp_path_factory) -> dict[int, Path]:
    """cores -> the example built for the host board, parallel where the plan says."""
    work = tmp_path_factory.mktemp("vision")
    with ThreadPoolExecutor(max_workers=2) as pool:
        built = dict(zip(CORES, pool.map(lambda n: build_cores(MODEL, work / f"c{n}", n, always=False), CORES)))
    for n in CORES[1:]:
        assert f"dataflow Vision: on {n} cores" in built[n][1], built[n][1]
    return {n: exe for n, (exe, _) in built.items()}


def test_the_example_checks_and_is_canonical():
    proc = cli("check", MODEL)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    proc = cli("fmt", "--check", MODEL)
    assert proc.returncode == 0 and proc.stdout == "", proc.stdout + proc.stderr


def test_analysis_predicts_a_speedup_of_at_least_1_7_on_two_cores():
    proc = cli("analyze", MODEL, "--cores", "2", "--json")
    assert proc.returncode == 0, proc.stderr
    flow = json.loads(proc.stdout)["dataflows"][0]
    assert flow["parallel"] and flow["speedup"] >= 1.7, flow
    assert flow["predicted_ns"] < 1_000_000 < flow["sequential_ns"], "the 1 ms period: kept on 2 cores, not on 1"


def _expected_offset(frame: int) -> int:
    """The offset of the line the camera draws in ``frame``: its column at
    the frame's middle row (the lean is symmetric about it), from the centre,
    in percent of half the width (the Camera actor's formula)."""
    width, phase = 160, frame % 240
    drift = phase - 60 if phase < 120 else 180 - phase
    column = width // 2 + int(drift * width / 240)
    return int((column - width // 2) * 100 / (width // 2))


def test_host_trace_is_the_same_on_1_2_and_4_cores_and_follows_the_line(programs, tmp_path):
    traces = {n: run(exe, tmp_path / f"c{n}.csv", duration=DURATION, stimulus=STIMULUS).trace_text
              for n, exe in programs.items()}
    assert traces[2] == traces[1]
    assert traces[4] == traces[1]
    from native_testlib import Trace
    trace = Trace(traces[1])
    for frame in range(40):
        at = 1000 * (frame + 1)  # frame k's result is published at the end of its period
        lost = 20 <= frame < 30
        assert trace.int("seen", at) == (0 if lost else 1), frame
        if lost:
            assert trace.int("drive.left.speed", at) == trace.int("drive.right.speed", at) == 0
        else:
            assert abs(trace.int("line", at) - _expected_offset(frame)) <= 2, frame


def test_local_execution_on_1_2_and_4_cores_gives_the_host_boards_trace(programs, tmp_path, capsys):
    host = run(programs[1], tmp_path / "host.csv", duration=DURATION, stimulus=STIMULUS).trace_text
    for cores in CORES:
        got = _local_trace(MODEL, tmp_path / f"local{cores}.csv", DURATION, STIMULUS, "--cores", str(cores))
        assert got == host, f"{cores} cores"
        if cores > 1:  # planned from the declared costs, as the host build is
            assert f"dataflow Vision: on {cores} cores" in capsys.readouterr().err


def _random_stimulus(path: Path, seed: int) -> Path:
    """Writes of the three params at random instants, within their ranges."""
    rng = random.Random(seed)
    rows = ["time_us,speed,steer_kp,steer_ki"]
    for t in sorted(rng.sample(range(0, 40), 6)):
        cells = [str(rng.randint(0, 255)) if rng.random() < 0.6 else "",
                 str(rng.randint(0, 8000)) if rng.random() < 0.6 else "",
                 str(rng.randint(0, 1000)) if rng.random() < 0.6 else ""]
        rows.append(f"{t * 1000 + rng.choice((0, 1000 - 1))}," + ",".join(cells))
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


@settings(max_examples=4, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1))
def test_random_stimuli_give_the_same_trace_on_1_2_and_4_cores(programs, tmp_path_factory, seed):
    work = tmp_path_factory.mktemp("vision_stim")
    stimulus = _random_stimulus(work / "stimulus.csv", seed)
    traces = {n: run(exe, work / f"c{n}.csv", duration=DURATION, stimulus=stimulus).trace_text
              for n, exe in programs.items()}
    assert traces[1].count("\n") > 20, stimulus.read_text()
    assert traces[2] == traces[1] == traces[4], stimulus.read_text()
