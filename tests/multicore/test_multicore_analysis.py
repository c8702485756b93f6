"""The multi-core plan (analysis/multicore.py) and ``easylab analyze
--cores``: on random SDF graphs (the generator of the random SDF tests)
every list schedule is valid, the precedence graph is the SDF semantics
(every order it allows finds the tokens each firing takes), the output is
the same every run; a build whose plan runs nothing in parallel is the
single-core build, byte for byte, and an MCU board refuses --cores."""

from __future__ import annotations

import json
import random
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from multicore_testlib import EXAMPLES, cli

from easylab.ir import multicore
from easylab.board.registry import load_board
from easylab.codegen.render import render
from easylab.pipeline import lower_file


def _rsdf():
    import test_native_sdf_random as rsdf
    return rsdf


def lowered(text: str):
    program, result = lower_file("random_sdf.elab", text=text)
    assert program is not None, result.report()
    return program


def check_schedule(fp: multicore.FiringPlan) -> None:
    """Each firing once, on one core, never before its predecessors end,
    never two at once on a core; critical path <= makespan <= sum of costs."""
    placed = sorted(f for lst in fp.order for f in lst)
    assert placed == list(range(len(fp.firings)))
    for c, lst in enumerate(fp.order):
        for a, b in zip(lst, lst[1:]):
            assert fp.start[a] + fp.cost[a] <= fp.start[b]
        assert all(fp.core[f] == c for f in lst)
    for f, preds in enumerate(fp.preds):
        for p in preds:
            assert fp.start[p] + fp.cost[p] <= fp.start[f], (fp.firings[p], fp.firings[f])
    assert fp.critical_path_ns <= fp.makespan_ns <= fp.sequential_ns


def check_tokens(program, fp: multicore.FiringPlan, order: list[int]) -> None:
    """Firing in ``order`` (any order the precedences allow), every firing
    finds the tokens it takes on each edge."""
    df = fp.dataflow
    tokens = {b.id: len(b.initial) for b in df.buffers}
    done: set[int] = set()
    for f in order:
        assert set(fp.preds[f]) <= done
        node = fp.firings[f][0]
        for b in df.buffers:
            if b.dst == node:
                assert tokens[b.id] >= b.cons, (fp.firings[f], b.src, b.dst)
                tokens[b.id] -= b.cons
        for b in df.buffers:
            if b.src == node:
                tokens[b.id] += b.prod
        done.add(f)
    assert tokens == {b.id: len(b.initial) for b in df.buffers}


def random_topological_order(preds, rng: random.Random) -> list[int]:
    waiting = [set(p) for p in preds]
    ready = [f for f, p in enumerate(waiting) if not p]
    order = []
    while ready:
        f = ready.pop(rng.randrange(len(ready)))
        order.append(f)
        for g, p in enumerate(waiting):
            if f in p:
                p.discard(f)
                if not p:
                    ready.append(g)
    return order


@settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(g=_rsdf().graphs(), cores=st.integers(1, 4), seed=st.integers(0, 2 ** 16))
def test_random_graphs_get_valid_schedules(g, cores, seed):
    program = lowered(_rsdf().elab(g))
    rng = random.Random(seed)
    costs = {f"G.{i.name}": rng.randint(1, 5000) for i in program.instances}
    plan = multicore.plan(program, cores, costs, always=True)
    for fp in plan.dataflows:
        check_schedule(fp)
        by_start = sorted(range(len(fp.firings)), key=lambda f: (fp.start[f], fp.core[f]))
        check_tokens(program, fp, by_start)
        check_tokens(program, fp, random_topological_order(fp.preds, rng))
        assert fp.parallel == (cores > 1 and fp.used_cores > 1)
    again = multicore.plan(program, cores, costs, always=True)
    assert again.summary() == plan.summary()


def test_list_schedule_of_a_fork_join_uses_both_cores():
    # 0 -> (1, 2, 3, 4) -> 5, equal costs: two cores halve the middle.
    preds = [(), (0,), (0,), (0,), (0,), (1, 2, 3, 4)]
    core, start, order = multicore.list_schedule(preds, [10] * 6, 2)
    assert max(s + 10 for s in start) == 40
    assert sorted(len(lst) for lst in order) == [2, 4]


def test_a_tiny_model_stays_on_one_core_and_says_so(tmp_path):
    blink = next(p for p in EXAMPLES if p.stem == "blink")
    proc = cli("build", blink, "--board", "host", "--cores", "2", "--cflags=-O0", "-o", tmp_path / "b")
    assert proc.returncode == 0, proc.stderr
    assert "nothing pays on more than one core: a single-core build" in proc.stdout
    single = cli("build", blink, "--board", "host", "--cflags=-O0", "-o", tmp_path / "s")
    assert (tmp_path / "b" / "model.c").read_bytes() == (tmp_path / "s" / "model.c").read_bytes()
    assert b"pthread_create" not in (tmp_path / "s" / "blink").read_bytes()
    assert "host: code" in single.stdout
    size = [ln for ln in proc.stdout.splitlines() if ln.startswith("host: code")]
    assert size == [ln for ln in single.stdout.splitlines() if ln.startswith("host: code")]


@pytest.mark.parametrize("model", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_a_plan_without_parallel_parts_changes_no_byte(model):
    program, result = lower_file(model)
    host = load_board("host")
    alone = render(program, host)
    for cores in (1, 2, 4):
        plan = multicore.plan(program, cores)
        if not plan.parallel:
            assert render(program, host, plan=plan) == alone
    assert "el_threads" not in alone["model.c"] and "EL_THREADS" not in alone["model.c"]


def test_mcu_boards_refuse_cores(tmp_path):
    blink = next(p for p in EXAMPLES if p.stem == "blink")
    proc = cli("build", blink, "--board", "avr", "--cores", "2", "-o", tmp_path / "avr")
    assert proc.returncode == 1
    assert "board 'avr' runs on one core" in proc.stderr


def test_analyze_cores_is_the_same_every_run_and_valid():
    cd = next(p for p in EXAMPLES if p.stem == "cd_to_dat")
    runs = [cli("analyze", cd, "--cores", "3", "--json") for _ in range(2)]
    assert runs[0].returncode == 0, runs[0].stderr
    assert runs[0].stdout == runs[1].stdout
    found = json.loads(runs[0].stdout)
    flow = found["dataflows"][0]
    assert flow["cores"] == 3 and flow["firings"] == 614
    assert sum(len(c) for c in flow["schedule"]) == 614
    assert flow["critical_path_ns"] <= flow["makespan_ns"] <= flow["sequential_ns"]
    text = cli("analyze", cd, "--cores", "3")
    assert text.returncode == 0 and "core 2:" in text.stdout and "predicted" in text.stdout


def test_analyze_profile_measures_every_actor(tmp_path):
    lf = next(p for p in EXAMPLES if p.stem == "line_follower")
    proc = cli("analyze", lf, "--cores", "2", "--profile", "--json")
    assert proc.returncode == 0, proc.stderr
    found = json.loads(proc.stdout)
    assert found["costs"] == "profile"
    program, _ = lower_file(lf)
    assert {f["name"] for f in found["dataflows"]} == {df.name for df in program.dataflows}


def test_profile_reads_firings_and_nanoseconds():
    from easylab.cli.profile import read_profile
    assert read_profile("G.a 4 1000\nG.b 0 0\nG.c 3 1\n") == {"G.a": 250, "G.c": 1}


def test_cores_must_be_a_positive_number(tmp_path):
    blink = next(p for p in EXAMPLES if p.stem == "blink")
    proc = cli("analyze", blink, "--cores", "0")
    assert proc.returncode == 2 and "the number of cores must be 1 to 64" in proc.stderr
    proc = cli("analyze", blink, "--profile")
    assert proc.returncode == 1 and "give --cores N too" in proc.stderr


ROBOT = EXAMPLES[0].parent / "robot" / "robot.elab"


def test_a_pc_node_says_its_cores_in_the_model(tmp_path):
    text = ROBOT.read_text(encoding="utf-8").replace("node planner board host", "node planner board host cores 2")
    program, result = lower_file(ROBOT, text=text)
    assert program is not None, result.report()
    assert {n.name: n.cores for n in program.deployment.nodes} == {"planner": 2, "joint1": 1, "joint2": 1}
    bad = text.replace("cores 2", "cores 0")
    program, result = lower_file(ROBOT, text=bad)
    assert program is None
    line = next(i for i, ln in enumerate(bad.splitlines(), 1) if "cores 0" in ln)
    col = bad.splitlines()[line - 1].index("0 \"PC") + 1
    assert f"robot.elab:{line}:{col}: error: node 'planner' has 0 cores: a node runs on 1 to 64" in result.report()


def test_an_mcu_node_with_cores_is_refused(tmp_path):
    model = tmp_path / "robot.elab"
    for f in ROBOT.parent.iterdir():
        if f.is_file():
            (tmp_path / f.name).write_bytes(f.read_bytes())
    model.write_text(ROBOT.read_text(encoding="utf-8").replace("mcu atmega328p \"shoulder", "mcu atmega328p cores 2 \"shoulder"),
                     encoding="utf-8")
    proc = cli("check", model)
    assert proc.returncode == 1
    assert "node 'joint1' (board avr, atmega328p): board 'avr' runs on one core" in proc.stderr


# A counter and a multiplier (COST: its `cost` line, or none), for the models below and others'.
SRC_AND_WORK = """\
actor type Src() {
    out y: uint32
    state n: uint32
    step {{ n = n + 1u; y = n; }}
}
actor type Work(m: uint32) {
    in  x: uint32
    out y: uint32
    COST
    step {{ y = x * m; }}
}
"""

FORK = "model fork\n" + SRC_AND_WORK + """\
actor type Add() {
    in  a: uint32
    in  b: uint32
    out y: uint32
    step {{ y = a + b; }}
}
var out: uint32
dataflow F {
    s  = Src()
    w1 = Work(m = 3)
    w2 = Work(m = 5)
    j  = Add()
    s.y  -> w1.x
    s.y  -> w2.x
    w1.y -> j.a
    w2.y -> j.b
    j.y  -> out
}
task t period 1 ms { run F }
"""


def test_a_declared_cost_decides_and_changes_no_id():
    heavy, result = lower_file("fork.elab", text=FORK.replace("COST", "cost 400 us"))
    assert heavy is not None, result.report()
    light, _ = lower_file("fork.elab", text=FORK.replace("COST", "cost 0.05 us"))
    assert [s.cost_ns for s in heavy.specs] == [None, 400_000, 400_000, None]  # Work(3), Work(5): two specs
    assert heavy.program_id == light.program_id
    (fp,) = multicore.plan(heavy, 2).dataflows
    assert fp.parallel and fp.makespan_ns < fp.sequential_ns
    assert {fp.firings[f][0] for f in fp.order[1]} in ({"w1"}, {"w2"})
    (fp,) = multicore.plan(light, 2).dataflows
    assert not fp.parallel and "parallel does not pay" in fp.reason


@pytest.mark.parametrize("cost, message", [
    ("cost 0 us", "must be whole nanoseconds from 0.001 us to 1 s"),
    ("cost 2 s", "must be whole nanoseconds from 0.001 us to 1 s"),
    ("cost 0.0005 us", "must be whole nanoseconds from 0.001 us to 1 s"),
    ("cost 3", "is a 'time'"),
    ("cost 1 us\n    cost 2 us", "at most one 'cost'"),
])
def test_a_bad_cost_is_an_error_at_its_place(cost, message):
    program, result = lower_file("fork.elab", text=FORK.replace("COST", cost))
    assert program is None
    report = result.report()
    assert message in report and ("fork.elab:10:" in report or "fork.elab:11:5" in report), report
