"""Property tests over random graphs (hypothesis), checked against an
independent firing-by-firing simulator."""

import math
from fractions import Fraction

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from easylab.analysis.sdf import (DeadlockError, InconsistentGraphError, SdfEdge, SdfGraph, analyze,
                                  repetition_vector, verify)
from sdf_testlib import consistent_graphs, cycle_completes, simulate

SETTINGS = settings(
    max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)


def components(graph):
    """Weakly connected components as sets of actor names."""
    parent = {a: a for a in graph.actors}

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for edge in graph.edges:
        parent[find(edge.src)] = find(edge.dst)
    groups = {}
    for a in graph.actors:
        groups.setdefault(find(a), set()).add(a)
    return list(groups.values())


any_live_graph = st.one_of(
    consistent_graphs(), consistent_graphs(cyclic=True), consistent_graphs(max_actors=8, cyclic=True)
)


@SETTINGS
@given(any_live_graph)
def test_repetition_vector_balances_with_gcd_one(graph):
    q = repetition_vector(graph)
    assert list(q) == list(graph.actors)
    assert all(count >= 1 for count in q.values())
    for edge in graph.edges:
        assert q[edge.src] * edge.prod == q[edge.dst] * edge.cons
    for members in components(graph):
        assert math.gcd(*(q[a] for a in members)) == 1


@SETTINGS
@given(any_live_graph, st.sampled_from(["sas", "min-buffer"]))
def test_schedules_are_admissible_and_periodic(graph, kind):
    analysis = analyze(graph, kind)
    peaks = simulate(graph, analysis.firings(), analysis.repetitions)
    sizes = verify(graph, analysis.schedule)
    assert sizes == peaks
    assert dict(analysis.buffers + analysis.self_loops) == peaks
    assert analysis.buffer_total == sum(size for _, size in analysis.buffers)
    assert analysis.buffer_total >= analysis.edge_lower_bound
    if kind == "min-buffer" and analysis.optimal is False:
        assert analysis.edge_bound_gap > 0


@SETTINGS
@given(st.one_of(consistent_graphs(), consistent_graphs(cyclic=True)))
def test_sas_names_each_actor_once_and_beats_flat(graph):
    analysis = analyze(graph, "sas")
    # Back edges carrying a whole iteration's tokens leave no component
    # tightly interdependent, so the schedule is single-appearance.
    assert analysis.single_appearance
    assert analysis.schedule.appearances() == {actor: 1 for actor in graph.actors}
    assert analysis.buffer_total >= analysis.sas_lower_bound
    assert analysis.flat_sas_total is not None
    assert analysis.buffer_total <= analysis.flat_sas_total


@SETTINGS
@given(consistent_graphs(max_actors=10, cyclic=True, delays="random"), st.sampled_from(["sas", "min-buffer"]))
def test_deadlock_reports_a_starving_cycle(graph, kind):
    try:
        analysis = analyze(graph, kind)
    except DeadlockError as error:
        cycle = error.edges
        assert cycle
        for edge, following in zip(cycle, cycle[1:] + cycle[:1]):
            assert edge.dst == following.src
        assert len({edge.src for edge in cycle}) == len(cycle)
        assert error.missing_edge in cycle and error.missing >= 1
        assert not cycle_completes(cycle)
        assert cycle_completes(cycle, error.missing_edge, error.missing)
        assert not cycle_completes(cycle, error.missing_edge, error.missing - 1)
        assert error.missing_edge.label in str(error) and f"needs {error.missing} more" in str(error)
    else:
        simulate(graph, analysis.firings(), analysis.repetitions)


@st.composite
def inconsistent_graphs(draw):
    """A consistent graph plus one edge inside a component whose rates break
    the balance; inserted anywhere, so the spanning tree may use it and
    blame an older edge."""
    graph = draw(consistent_graphs(max_actors=12, cyclic=draw(st.booleans())))
    q = repetition_vector(graph)
    members = sorted(draw(st.sampled_from(components(graph))))
    src, dst = draw(st.sampled_from(members)), draw(st.sampled_from(members))
    prod = draw(st.integers(1, 12))
    cons = draw(st.integers(1, 12).filter(lambda c: q[src] * prod != q[dst] * c))
    edges = list(graph.edges)
    edges.insert(draw(st.integers(0, len(edges))), SdfEdge(src, dst, prod, cons))
    return SdfGraph(graph.actors, edges)


@SETTINGS
@given(inconsistent_graphs())
def test_inconsistency_reports_a_contradicting_cycle(graph):
    with pytest.raises(InconsistentGraphError) as caught:
        repetition_vector(graph)
    cycle = caught.value.edges
    assert cycle
    # An undirected closed walk: start at the first edge's source.
    start = at = cycle[0].src
    gain = Fraction(1)
    for edge in cycle:
        if edge.src == at:
            gain *= Fraction(edge.prod, edge.cons)
            at = edge.dst
        else:
            assert edge.dst == at
            gain *= Fraction(edge.cons, edge.prod)
            at = edge.src
    assert at == start
    assert gain != 1
    for edge in cycle:
        assert edge.label in str(caught.value)
