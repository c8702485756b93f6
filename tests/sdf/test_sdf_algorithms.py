"""The algorithms against brute force, and special graph shapes."""

import importlib.util
import json
import math
import time
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from easylab.analysis.sdf import DeadlockError, SdfGraph, analyze, check_deadlock, repetition_vector, verify
from easylab.analysis.sdf.dppo import dppo, nesting_cost
from sdf_testlib import consistent_graphs, simulate


def brute_force_nesting(counts, edges, lo, hi):
    """Cheapest bracketing of positions lo..hi by trying every split."""
    if lo == hi:
        return 0
    g = math.gcd(*counts[lo:hi + 1])
    best = None
    for k in range(lo, hi):
        crossing = sum(w for a, b, w in edges if lo <= a <= k < b <= hi)
        cost = (brute_force_nesting(counts, edges, lo, k)
                + brute_force_nesting(counts, edges, k + 1, hi) + crossing // g)
        best = cost if best is None else min(best, cost)
    return best


@settings(max_examples=150, deadline=None)
@given(st.data())
def test_dppo_matches_brute_force(data):
    m = data.draw(st.integers(1, 7))
    counts = data.draw(st.lists(st.sampled_from([1, 2, 3, 4, 6, 12]), min_size=m, max_size=m))
    pairs = [(a, b) for a in range(m) for b in range(a + 1, m)]
    chosen = data.draw(st.lists(st.sampled_from(pairs), max_size=8)) if pairs else []
    # Traffic per iteration is a multiple of the consumer's count.
    edges = [(a, b, counts[b] * data.draw(st.integers(1, 5))) for a, b in chosen]
    cost, splits = dppo(counts, edges)
    assert cost == brute_force_nesting(counts, edges, 0, m - 1)
    assert nesting_cost(counts, edges, splits) == cost


def brute_force_min_buffer(graph, q):
    """Least total peak buffer over every firing order (tiny graphs only)."""
    edges = [e for e in graph.edges]
    actors = list(graph.actors)
    best = [None]
    seen = set()

    def explore(fired, tokens, peaks):
        state = (fired, peaks)
        if state in seen or (best[0] is not None and sum(peaks) >= best[0]):
            return
        seen.add(state)
        if all(fired[i] == q[a] for i, a in enumerate(actors)):
            best[0] = sum(peaks)
            return
        for i, a in enumerate(actors):
            if fired[i] == q[a]:
                continue
            new_tokens = list(tokens)
            ok = True
            for j, e in enumerate(edges):
                if e.dst == a:
                    new_tokens[j] -= e.cons
                    ok = ok and new_tokens[j] >= 0
            if not ok:
                continue
            for j, e in enumerate(edges):
                if e.src == a:
                    new_tokens[j] += e.prod
            new_peaks = tuple(max(p, t) for p, t in zip(peaks, new_tokens))
            explore(fired[:i] + (fired[i] + 1,) + fired[i + 1:], tuple(new_tokens), new_peaks)

    start = tuple(e.delay for e in edges)
    explore(tuple(0 for _ in actors), start, start)
    return best[0]


@settings(max_examples=60, deadline=None)
@given(consistent_graphs(max_actors=4, cyclic=True, delays="random"))
def test_min_buffer_is_optimal_on_tiny_graphs(graph):
    graph = SdfGraph(graph.actors, [e for e in graph.edges if not e.is_self_loop])
    try:
        check_deadlock(graph)
    except DeadlockError:
        return
    q = repetition_vector(graph)
    if sum(q.values()) > 10:
        return
    analysis = analyze(graph, "min-buffer")
    assert analysis.optimal
    assert analysis.buffer_total == brute_force_min_buffer(graph, q)


def test_tightly_interdependent_component_gets_a_valid_looped_schedule():
    # The back edge holds 4 tokens, less than the 6 one iteration moves.
    graph = SdfGraph.from_edges([("A", "B", 2, 3), ("B", "A", 3, 2, 4), ("B", "C", 1, 1), ("C", "D", 2, 1)])
    analysis = analyze(graph, "sas")
    assert not analysis.single_appearance
    assert "tightly interdependent" in analysis.method
    assert analysis.flat_sas_total is None
    assert analysis.schedule.appearances()["C"] == 1
    simulate(graph, analysis.firings(), analysis.repetitions)


def test_loosely_interdependent_cycles_nest():
    # Outer cycle A..D broken by a delay covering one iteration; inside it,
    # the cycle B <-> C carries enough for one of its own sub-iterations only.
    graph = SdfGraph.from_edges([
        ("A", "B", 2, 1), ("B", "C", 1, 1), ("C", "B", 1, 1, 1), ("C", "D", 1, 2), ("D", "A", 1, 1, 1),
    ])
    analysis = analyze(graph, "sas")
    assert analysis.single_appearance
    assert analysis.schedule_text == "A(2BC)D"
    assert analysis.flat_sas_total is None   # B and C cannot fire all at once
    simulate(graph, analysis.firings(), analysis.repetitions)


def test_disconnected_graph_and_isolated_actors():
    graph = SdfGraph.from_edges([("A", "B", 2, 4), ("C", "D", 3, 1)], actors=["Z"])
    assert repetition_vector(graph) == {"Z": 1, "A": 2, "B": 1, "C": 1, "D": 3}
    for kind in ("sas", "min-buffer"):
        analysis = analyze(graph, kind)
        assert sum(verify(graph, analysis.schedule).values()) == analysis.buffer_total == 4 + 3


def test_empty_graph():
    analysis = analyze(SdfGraph())
    assert analysis.schedule_text == "" and analysis.buffer_total == 0
    assert analysis.to_json_dict("none")["repetitions"] == {}


def test_parallel_edges_with_delays():
    graph = SdfGraph.from_edges([("A", "B", 2, 3), ("A", "B", 2, 3, 5), ("B", "A", 3, 2, 6)])
    for kind in ("sas", "min-buffer"):
        analysis = analyze(graph, kind)
        simulate(graph, analysis.firings(), analysis.repetitions)


def test_deep_chain_reaches_the_sas_lower_bound_without_recursion():
    # Counts halve along the chain: the best SAS nests one loop per actor.
    n = 1200
    graph = SdfGraph.from_edges([(f"x{i}", f"x{i + 1}", 1, 2) for i in range(n - 1)])
    analysis = analyze(graph, "sas")
    assert analysis.buffer_total == analysis.sas_lower_bound == 2 * (n - 1)
    assert analysis.schedule_text.startswith("(2 (2 (2")
    assert analysis.repetitions["x0"] == 2 ** (n - 1)


def test_ten_thousand_actors_with_large_counts():
    # Counts up to 2**12 along a chain with a feedback edge: the deadlock
    # check fires in batches, so it is fast regardless of the counts.
    n = 10_000
    graph = SdfGraph()
    for i in range(n - 1):
        graph.add_edge(f"n{i}", f"n{i + 1}", *((2, 1) if (i // 12) % 2 == 0 else (1, 2)))
    q = repetition_vector(graph)
    first, last = q["n0"], q[f"n{n - 1}"]
    g = math.gcd(first, last)
    # Feedback carrying one whole iteration's tokens.
    graph.add_edge(f"n{n - 1}", "n0", first // g, last // g, first * last // g)
    assert max(repetition_vector(graph).values()) == 2 ** 12
    start = time.perf_counter()
    check_deadlock(graph)
    analysis = analyze(graph, "sas")
    assert time.perf_counter() - start < 30
    assert analysis.single_appearance
    assert analysis.buffer_total <= analysis.flat_sas_total


def test_bench_script_smoke(tmp_path):
    path = Path(__file__).resolve().parents[2] / "bench" / "bench_sdf.py"
    spec = importlib.util.spec_from_file_location("bench_sdf", path)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    rows = bench.main(tmp_path, sizes=(40,))
    report = json.loads((tmp_path / "sdf.json").read_text())
    assert len(rows) == len(report["results"]) == 3
    for row in report["results"]:
        assert row["sas_total"] <= row["flat_sas_total"]
        assert row["sas_total"] >= row["sas_lower_bound"]
