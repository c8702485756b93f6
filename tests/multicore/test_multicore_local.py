"""Local execution on several cores (`easylab run --cores N`): the runner
runs the IR's multi-core plan as jobs on worker threads, and the trace is
the single-core trace and the host board's, byte for byte: every example
on 1, 2 and 4 cores, and random SDF graphs on random plans (random costs,
hence random placements and waits across cores) against their reference.
Without --cores nothing changes."""

from __future__ import annotations

import ctypes
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from multicore_testlib import DATA, EXAMPLES, build_cores, run
from test_multicore_analysis import SRC_AND_WORK
from test_multicore_traces import DURATIONS

from easylab.cli import main as easylab_main
from easylab.interp import runner as R
from easylab.interp.clock import Clock
from easylab.interp.engine import Engine
from easylab.interp.plugins import PluginCache
from easylab.interp.stimulus import load as load_stimulus
from easylab.interp.trace import TraceWriter, columns_of
from easylab.ir import multicore
from easylab.pipeline import lower_file


def _lower(path: Path):
    program, result = lower_file(path)
    assert program is not None, result.report()
    return program


def _local_trace(model: Path, trace: Path, duration: str, stimulus: Path | None, *extra: str) -> str:
    """``easylab run MODEL --fast ...`` in this process; its trace."""
    argv = ["run", str(model), "--fast", "--duration", duration, "--trace", str(trace), *extra]
    if stimulus is not None:
        argv += ["--stimulus", str(stimulus)]
    assert easylab_main(argv) == 0
    return trace.read_text()


@pytest.mark.parametrize("model", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_trace_on_1_2_and_4_cores_is_the_host_boards(model, tmp_path):
    duration, stimulus = DURATIONS[model.stem], DATA / f"{model.stem}.stimulus.csv"
    exe, _ = build_cores(model, tmp_path / "host", 1, cflags="-O0")
    host = run(exe, tmp_path / "host.csv", duration=duration, stimulus=stimulus).trace_text
    assert host.count("\n") > 2, "no instant traced"
    assert _local_trace(model, tmp_path / "plain.csv", duration, stimulus) == host
    for cores in (1, 2, 4):
        got = _local_trace(model, tmp_path / f"c{cores}.csv", duration, stimulus,
                           "--cores", str(cores), "--parallel", "always")
        assert got == host, f"{cores} cores"


class PlannedEngine(Engine):
    """An engine on a given multi-core plan's costs (random placements)."""

    def __init__(self, *args, costs: dict[str, int], **kwargs):
        self.costs = costs
        super().__init__(*args, **kwargs)

    def multicore_plan(self, program):
        return multicore.plan(program, self.cores, self.costs, always=True)


def _run_engine(engine: Engine, duration_us: int) -> None:
    engine.run(duration_us)
    engine.shutdown()


def _random_sdf():
    import test_native_sdf_random as rsdf
    return rsdf


@settings(max_examples=8, deadline=None, derandomize=True, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                 HealthCheck.data_too_large])
@given(g=_random_sdf().graphs(), cores=st.integers(2, 4), seed_costs=st.lists(st.integers(1, 5000), min_size=16,
                                                                              max_size=16))
def test_random_dataflow_on_a_random_plan_gives_the_reference_values(g, cores, seed_costs, tmp_path_factory):
    rsdf = _random_sdf()
    from native_testlib import Trace

    work = tmp_path_factory.mktemp("mc_local_rsdf")
    model = work / "random_sdf.elab"
    model.write_text(rsdf.elab(g), encoding="utf-8")
    program = _lower(model)
    flow = program.dataflows[0]
    nodes = sorted({node for node in flow.schedule.firings()})
    costs = {f"{flow.name}.{node}": seed_costs[k % len(seed_costs)] * (k + 1) for k, node in enumerate(nodes)}
    duration_us = (rsdf.ACTIVATIONS + 1) * 1000
    traces = {}
    for n in (1, cores):
        path = work / f"c{n}.csv"
        engine = PlannedEngine(program, PluginCache(), None, TraceWriter(str(path), program, columns_of(program)),
                               cores=n, costs=costs)
        _run_engine(engine, duration_us)
        traces[n] = path.read_text()
        if n > 1:
            found = multicore.plan(program, n, costs, always=True)
            job = engine.state.dataflows[0].job
            if found.dataflows[0].used_cores > 1:  # the job ran once per activation
                assert job is not None and job.struct.epoch == rsdf.ACTIVATIONS + 1
            else:
                assert job is None
    assert traces[cores] == traces[1], model.read_text()
    trace = Trace(traces[cores])
    for name, values in rsdf.reference(g, rsdf.ACTIVATIONS).items():
        assert [trace.int(name, 1000 * (a + 1)) for a in range(rsdf.ACTIVATIONS)] == values, model.read_text()


def _ops_of(engine: Engine) -> list[int]:
    table = engine.state.table.ops
    return [table.array[k].kind for k in range(table.count)]


def test_without_cores_a_run_has_no_job_and_where_nothing_pays_neither():
    blink = next(p for p in EXAMPLES if p.stem == "blink")
    cd = next(p for p in EXAMPLES if p.stem == "cd_to_dat")
    for model, cores in ((cd, 1), (blink, 2)):
        engine = Engine(_lower(model), PluginCache(), cores=cores)
        assert engine.state.multicore is None
        assert all(d is None or d.job is None for d in engine.state.dataflows)
        assert R.PARALLEL not in _ops_of(engine)


def test_run_says_what_runs_on_the_cores(tmp_path, capsys):
    blink = next(p for p in EXAMPLES if p.stem == "blink")
    _local_trace(blink, tmp_path / "b.csv", "1s", None, "--cores", "2")
    assert "easylab run: 2 cores: nothing pays on more than one core: a single-core run" in capsys.readouterr().err
    from test_multicore_analysis import FORK

    fork = tmp_path / "fork.elab"  # two branches of 400 us a firing: parallel pays
    fork.write_text(FORK.replace("COST", "cost 400 us"), encoding="utf-8")
    single = _local_trace(fork, tmp_path / "f1.csv", "20ms", None)
    capsys.readouterr()
    assert _local_trace(fork, tmp_path / "f2.csv", "20ms", None, "--cores", "2") == single
    assert "easylab run: dataflow F: on 2 cores (saves" in capsys.readouterr().err


TWO_TASKS = "model two_tasks\n" + SRC_AND_WORK.replace("    COST\n", "") + """\
var a: uint32
var b: uint32
dataflow A {
    s = Src()
    w = Work(m = 3)
    s.y -> w.x
    w.y -> a
}
dataflow B {
    s = Src()
    w = Work(m = 7)
    s.y -> w.x
    w.y -> b
}
task ta period 2 ms { run A }
task tb period 2 ms { run B }
"""


def test_tasks_released_together_run_as_one_job(tmp_path):
    """Two tasks of dataflows released at the same instants: one job,
    each task on its core, run once per release; the single-core trace."""
    model = tmp_path / "two_tasks.elab"
    model.write_text(TWO_TASKS, encoding="utf-8")
    program = _lower(model)
    traces = {}
    for cores, pace in ((1, None), (2, None), (2, 50.0)):  # virtual time, and paced (bodies one instant at a time)
        path = tmp_path / f"c{cores}_{pace}.csv"
        engine = Engine(program, PluginCache(), None, TraceWriter(str(path), program, columns_of(program)),
                        cores=cores, always_parallel=True)
        jobs = [job for job in engine.state.group_jobs.values() if job is not None]
        assert len(jobs) == (cores > 1)
        engine.run(20_000, Clock(pace))
        engine.shutdown()
        assert all(job.struct.epoch == 10 for job in jobs)
        traces[cores, pace] = path.read_text()
    assert traces[2, None] == traces[1, None]
    assert traces[2, 50.0] == traces[1, None]
    traces[1] = traces[1, None]
    assert traces[1].splitlines()[-1] == "18000,27,63"  # a = 3n, b = 7n, published at the deadline


def test_a_fault_on_one_core_stops_the_job_without_a_hang():
    """Core 1 reads past its staging array before the firing core 0 waits
    for: the job ends with that fault (not with core 0's abandoned wait),
    and the job runs again afterwards."""
    from easylab.core import types as T
    from easylab.interp import values as V

    runner = PluginCache().runner
    stage = R.Stage(T.INT16, 0)  # no token to read
    target = (V.ctype(T.INT16) * 1)()
    job, flags = R.Job(2), R.Flags(1)
    job.set_lists([[R.wait(flags[0], job)],
                   [R.read(stage, ctypes.addressof(target), T.INT16, True), R.signal(flags[0], job)]])
    plan = R.OpList([R.parallel(job)])
    with pytest.raises(R.RunnerFault) as fault:
        runner.run(plan.all, R.Cursor())
    assert (fault.value.kind, fault.value.at) == (R.STAGE, stage.address)
    stage.struct.tokens = 1  # now there is one: the next run goes through
    runner.run(plan.all, R.Cursor())
    assert job.struct.epoch == 2 and flags.array[0] == 2


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_model_trace_is_the_same_on_1_2_and_4_cores(seed, tmp_path):
    """A fixed sample of the back-to-back random models (charts, channels,
    tasks at several rates), as tests/multicore/test_multicore_traces.py
    builds them for the host board."""
    from crosscheck import write_case
    from modelgen import generate
    from modes import MODES

    generated = generate(seed, MODES["host"][0])
    case = write_case(tmp_path, generated.name, generated.text, generated.stimulus, generated.duration_ms)
    duration = f"{case.duration_ms}ms"
    single = _local_trace(case.model, tmp_path / "c1.csv", duration, case.stimulus)
    assert single.count("\n") > 2
    for cores in (2, 4):
        got = _local_trace(case.model, tmp_path / f"c{cores}.csv", duration, case.stimulus,
                           "--cores", str(cores), "--parallel", "always")
        assert got == single, (cores, case.model)


TSAN_HARNESS = r"""
#include "runner.c"
#include <stdio.h>

#define FIRINGS 16
static int32_t produced[FIRINGS], consumed[FIRINGS];

static void produce(void *state, const void *const *in, void *const *out, const void *const *params)
{
    int32_t *n = state;
    (void)in; (void)params;
    *n += 1;
    *(int32_t *)out[0] = *n;
}

static void consume(void *state, const void *const *in, void *const *out, const void *const *params)
{
    (void)state; (void)params;
    *(int32_t *)out[0] = 2 * *(const int32_t *)in[0];
}

int main(void)
{
    static el_op_t lists[2][2 * FIRINGS], plan[1];
    static const el_op_t *heads[2] = {lists[0], lists[1]};
    static uint32_t counts[2] = {2 * FIRINGS, 2 * FIRINGS};
    static el_cursor_t cursors[2], cursor;
    static uint64_t flags[FIRINGS];
    static void *outs[FIRINGS], *ins[FIRINGS], *outs2[FIRINGS];
    static int32_t counter;
    static el_job_t job;
    int k, run;
    job.cores = 2u; job.lists = heads; job.counts = counts; job.cursors = cursors;
    for (k = 0; k < FIRINGS; k++) {
        outs[k] = &produced[k]; ins[k] = &produced[k]; outs2[k] = &consumed[k];
        lists[0][2 * k] = (el_op_t){.kind = EL_OP_FIRE, .fn = produce, .object = &counter,
                                    .outputs = (void *const *)&outs[k]};
        lists[0][2 * k + 1] = (el_op_t){.kind = EL_OP_SIGNAL, .object = &flags[k], .src = &job};
        lists[1][2 * k] = (el_op_t){.kind = EL_OP_WAIT, .object = &flags[k], .src = &job};
        lists[1][2 * k + 1] = (el_op_t){.kind = EL_OP_FIRE, .fn = consume, .inputs = (const void *const *)&ins[k],
                                        .outputs = (void *const *)&outs2[k]};
    }
    plan[0] = (el_op_t){.kind = EL_OP_PARALLEL, .object = &job};
    for (run = 0; run < 200; run++) {
        if (el_run_ops(plan, 1u, &cursor) != EL_RUN_OK) {
            return 2;
        }
        for (k = 0; k < FIRINGS; k++) {
            if (consumed[k] != 2 * (run * FIRINGS + k + 1)) {
                printf("run %d firing %d: %d\n", run, k, (int)consumed[k]);
                return 1;
            }
        }
    }
    return 0;
}
"""


def test_thread_sanitizer_finds_nothing_in_the_runners_jobs(tmp_path):
    """runner.c's jobs (posting, WAIT and SIGNAL across two cores, the
    join), built with ThreadSanitizer and run 200 times: right values,
    no report."""
    import subprocess

    from easylab.interp.runner import SOURCE

    harness = tmp_path / "harness.c"
    harness.write_text(TSAN_HARNESS, encoding="utf-8")
    exe = tmp_path / "harness"
    build = subprocess.run(["gcc", "-std=c99", "-O1", "-g", "-Wall", "-Wextra", "-Werror", "-D_POSIX_C_SOURCE=200809L",
                            "-fsanitize=thread", f"-I{SOURCE.parent}", "-o", str(exe), str(harness), "-pthread"],
                           capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    proc = subprocess.run([str(exe)], capture_output=True, text=True, timeout=120)
    assert (proc.returncode, proc.stdout, proc.stderr) == (0, "", "")


FORKED = """
import os, sys
from easylab.pipeline import lower_file
from easylab.interp.engine import Engine
from easylab.interp.plugins import PluginCache

program, _ = lower_file(sys.argv[1])
Engine(program, PluginCache(), cores=2, always_parallel=True).run(5000)
pid = os.fork()
if pid == 0:  # the parent's worker threads are not in the child: it starts its own
    engine = Engine(program, PluginCache(), cores=2, always_parallel=True)
    engine.run(5000)
    os._exit(0 if engine.state.dataflows[0].job.struct.epoch == 5 else 3)
_, status = os.waitpid(pid, 0)
sys.exit(os.waitstatus_to_exitcode(status))
"""


def test_a_forked_child_runs_jobs_on_its_own_threads(tmp_path):
    import subprocess
    import sys

    from test_multicore_analysis import FORK

    model = tmp_path / "fork.elab"
    model.write_text(FORK.replace("COST", ""), encoding="utf-8")
    proc = subprocess.run([sys.executable, "-c", FORKED, str(model)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
