"""Multi-core builds of the host board give the single-core trace, byte
for byte, on 1, 2 and 4 cores, parallel whatever the prediction says:
every example and a fixed sample of the back-to-back random models
(tests/crosscheck/modelgen.py); random SDF graphs (the generator of
tests/native/test_native_sdf_random.py) on 2 and 4 cores against its
reference. A ThreadSanitizer build of a parallel model runs with no
report."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, settings

from multicore_testlib import DATA, EXAMPLES, build_cores, run

CORES = (1, 2, 4)
# How long each example runs against data/<example>.stimulus.csv (virtual time).
DURATIONS = {"blink": "1s", "cd_to_dat": "100ms", "line_follower": "1s", "pneumatic_cylinder": "3600ms",
             "pt100_sensor": "2s"}


def traces_on_cores(model: Path, work: Path, duration: str, stimulus: Path | None,
                    cflags: str = "-O0", cores: tuple[int, ...] = CORES) -> dict[int, str]:
    """cores -> the trace of ``model`` built for that many cores."""
    with ThreadPoolExecutor(max_workers=2) as pool:
        exes = dict(zip(cores, pool.map(lambda n: build_cores(model, work / f"c{n}", n, cflags=cflags)[0], cores)))
    return {n: run(exe, work / f"c{n}.csv", duration=duration, stimulus=stimulus).trace_text
            for n, exe in exes.items()}


@pytest.mark.parametrize("model", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_trace_is_the_same_on_1_2_and_4_cores(model, tmp_path):
    traces = traces_on_cores(model, tmp_path, DURATIONS[model.stem], DATA / f"{model.stem}.stimulus.csv")
    assert traces[1].count("\n") > 2, "no instant traced"
    assert traces[2] == traces[1]
    assert traces[4] == traces[1]


def _random_sdf():
    import test_native_sdf_random as rsdf
    return rsdf


@settings(max_examples=3, deadline=None, derandomize=True, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                 HealthCheck.data_too_large])
@given(g=_random_sdf().graphs())
def test_random_dataflow_trace_is_the_same_on_1_2_and_4_cores(g, tmp_path_factory):
    rsdf = _random_sdf()
    work = tmp_path_factory.mktemp("mc_rsdf")
    model = work / "random_sdf.elab"
    model.write_text(rsdf.elab(g), encoding="utf-8")
    # One core's values are the reference's (tests/native/test_native_sdf_random.py): 2 and 4 against it.
    traces = traces_on_cores(model, work, f"{rsdf.ACTIVATIONS + 1}ms", None, cores=(2, 4))
    expected = rsdf.reference(g, rsdf.ACTIVATIONS)
    from native_testlib import Trace
    trace = Trace(traces[4])
    for name, values in expected.items():
        assert [trace.int(name, 1000 * (a + 1)) for a in range(rsdf.ACTIVATIONS)] == values, model.read_text()
    assert traces[2] == traces[4]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_model_trace_is_the_same_on_1_2_and_4_cores(seed, tmp_path):
    from crosscheck import write_case
    from modelgen import generate
    from modes import MODES

    generated = generate(seed, MODES["host"][0])
    case = write_case(tmp_path, generated.name, generated.text, generated.stimulus, generated.duration_ms)
    traces = traces_on_cores(case.model, tmp_path, f"{case.duration_ms}ms", case.stimulus)
    assert traces[2] == traces[1], case.model
    assert traces[4] == traces[1], case.model


def test_thread_sanitizer_finds_nothing_in_a_parallel_build(tmp_path):
    """cd_to_dat's 614 firings per iteration on 4 cores (hundreds of waits
    across cores), and line_follower's tasks released together on 2."""
    for name, cores, duration in (("cd_to_dat", 4, "40ms"), ("line_follower", 2, "1s")):
        model = next(p for p in EXAMPLES if p.stem == name)
        exe, out = build_cores(model, tmp_path / name, cores, cflags="-fsanitize=thread -g -O1")
        assert f"on {cores} cores" in out
        r = run(exe, tmp_path / f"{name}.csv", duration=duration, stimulus=DATA / f"{name}.stimulus.csv")
        assert r.proc.stderr == ""  # run() insists on it too: a report goes there
