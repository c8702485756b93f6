"""Error paths: malformed graphs, inconsistent rates, deadlocks, bad schedules."""

import re

import pytest

from easylab.analysis.sdf import (DeadlockError, Fire, GraphError, InconsistentGraphError, Loop, Schedule,
                                  ScheduleError, SdfEdge, SdfGraph, SdfOptions, analyze, check_deadlock,
                                  repetition_vector, verify)
from sdf_testlib import cycle_completes


@pytest.mark.parametrize(
    "spec",
    [
        ("A", "B", 0, 1), ("A", "B", 1, -2), ("A", "B", 1, 1, -1), ("A", "B", True, 1),
        ("A", "B", 1.0, 1), ("", "B", 1, 1), ("A", None, 1, 1),
    ],
)
def test_malformed_edges_are_refused(spec):
    with pytest.raises(GraphError):
        SdfGraph().add_edge(*spec)


def test_duplicate_actor_is_refused():
    graph = SdfGraph(["A"])
    with pytest.raises(GraphError, match="duplicate actor 'A'"):
        graph.add_actor("A")


def test_inconsistent_two_actor_cycle():
    graph = SdfGraph()
    forward = graph.add_edge("A", "B", 2, 1, name="a.y -> b.x", loc=("model.elab", 3))
    backward = graph.add_edge("B", "A", 1, 1, name="b.y -> a.x", loc=("model.elab", 4))
    with pytest.raises(InconsistentGraphError) as caught:
        repetition_vector(graph)
    error = caught.value
    assert set(map(id, error.edges)) == {id(forward), id(backward)}
    assert {edge.loc for edge in error.edges} == {("model.elab", 3), ("model.elab", 4)}
    message = str(error)
    assert "a.y -> b.x (2:1)" in message and "b.y -> a.x (1:1)" in message
    assert re.search(r"from ([AB]), \1 would have to fire (2|1/2) times as often as itself", message)
    # analyze and check_deadlock report the same.
    with pytest.raises(InconsistentGraphError):
        analyze(graph)
    with pytest.raises(InconsistentGraphError):
        check_deadlock(graph)


def test_inconsistent_parallel_edges_and_self_loop():
    graph = SdfGraph.from_edges([("A", "B", 1, 1), ("A", "B", 2, 1)])
    with pytest.raises(InconsistentGraphError) as caught:
        repetition_vector(graph)
    assert len(caught.value.edges) == 2
    graph = SdfGraph.from_edges([("A", "A", 2, 1)])
    with pytest.raises(InconsistentGraphError) as caught:
        repetition_vector(graph)
    assert caught.value.edges == list(graph.edges)


def test_inconsistent_long_cycle_is_the_tree_path_plus_closing_edge():
    # A chain a0..a5 closed by an edge whose rates disagree with the chain.
    graph = SdfGraph.from_edges([(f"a{i}", f"a{i + 1}", 2, 1) for i in range(5)] + [("a0", "a5", 1, 1)])
    with pytest.raises(InconsistentGraphError) as caught:
        repetition_vector(graph)
    assert len(caught.value.edges) == 6


@pytest.mark.parametrize(
    "forward, backward, expected",
    [
        ((2, 3, 0), (3, 2, 0), 4),   # prod + cons - gcd tokens in total
        ((2, 3, 0), (3, 2, 2), 2),
        ((1, 1, 0), (1, 1, 0), 1),
        ((4, 6, 1), (6, 4, 1), 7),   # odd delays with even rates waste one
    ],
)
def test_deadlocked_two_actor_cycle_needs_n_tokens(forward, backward, expected):
    graph = SdfGraph()
    graph.add_edge("A", "B", *forward, name="A.y -> B.x")
    graph.add_edge("B", "A", *backward, name="B.y -> A.x")
    with pytest.raises(DeadlockError) as caught:
        analyze(graph)
    error = caught.value
    assert error.missing == expected
    assert error.missing_edge in error.edges and len(error.edges) == 2
    message = str(error)
    plural = "s" if expected != 1 else ""
    assert f"edge {error.missing_edge.label} needs {expected} more initial token{plural}" in message
    assert not cycle_completes(error.edges)
    assert cycle_completes(error.edges, error.missing_edge, expected)
    assert not cycle_completes(error.edges, error.missing_edge, expected - 1)


def test_deadlock_cycle_excludes_innocent_actors():
    # src -> x <-> y -> sink: only x and y starve.
    graph = SdfGraph.from_edges(
        [("src", "x", 1, 1), ("x", "y", 1, 1), ("y", "x", 1, 1), ("y", "sink", 1, 1)]
    )
    with pytest.raises(DeadlockError) as caught:
        check_deadlock(graph)
    assert {(e.src, e.dst) for e in caught.value.edges} == {("x", "y"), ("y", "x")}
    assert caught.value.missing == 1


def test_self_loop_without_tokens_deadlocks():
    graph = SdfGraph.from_edges([("A", "A", 2, 2, 1), ("A", "B", 1, 1)])
    with pytest.raises(DeadlockError) as caught:
        analyze(graph)
    assert caught.value.edges == [graph.edges[0]] and caught.value.missing == 1


def test_verify_rejects_bad_schedules():
    graph = SdfGraph.from_edges([("A", "B", 2, 3)])
    good = Schedule((Fire("A", 3), Fire("B", 2)))
    assert verify(graph, good) == {graph.edges[0]: 6}
    with pytest.raises(ScheduleError, match="would need 6 more tokens"):
        verify(graph, Schedule((Fire("B", 2), Fire("A", 3))))
    with pytest.raises(ScheduleError, match="fires 2 times, but one iteration fires it 3"):
        verify(graph, Schedule((Fire("A", 2), Fire("B", 2))))
    with pytest.raises(ScheduleError, match="unknown actor 'C'"):
        verify(graph, Schedule((Fire("C"),)))
    with pytest.raises(ScheduleError, match="more than its buffer of 4"):
        verify(graph, good, {graph.edges[0]: 4})
    interleaved = Schedule((Fire("A", 2), Fire("B"), Fire("A"), Fire("B")))
    assert verify(graph, interleaved, {graph.edges[0]: 4}) == {graph.edges[0]: 4}
    assert verify(graph, Schedule((Loop(1, (Fire("A", 3), Fire("B", 2))),))) == {graph.edges[0]: 6}


def test_analyze_rejects_unknown_kind_and_huge_flat_schedules():
    graph = SdfGraph.from_edges([("A", "B", 1000, 1)])
    with pytest.raises(ValueError, match="schedule must be one of"):
        analyze(graph, "fastest")
    with pytest.raises(ScheduleError, match="1001 firings per iteration"):
        analyze(graph, "min-buffer", SdfOptions(max_flat_firings=1000))
    assert analyze(graph, "sas").buffer_total == 1000


def test_edges_compare_by_identity():
    a = SdfEdge("A", "B", 1, 1)
    b = SdfEdge("A", "B", 1, 1)
    assert a != b and len({a, b}) == 2
