"""The analysis cache (analysis/sdf/cache.py): for a graph equal to one it
has analysed, the same analysis as analyze() gives, on the new graph's own
edge objects; errors raised as analyze() raises them; every distinct
graph analysed once."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from easylab.analysis.sdf import AnalysisCache, SdfEdge, SdfGraph, SdfError, analyze
from sdf_testlib import consistent_graphs

SETTINGS = settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def rebuilt(graph: SdfGraph, tag: str) -> SdfGraph:
    """An equal graph of new edge objects (another ``loc``, as after an edit that moved the text)."""
    return SdfGraph(graph.actors, [SdfEdge(e.src, e.dst, e.prod, e.cons, e.delay, e.name, loc=(tag, i))
                                   for i, e in enumerate(graph.edges)], name=graph.name)


def outcome(graph: SdfGraph, analyse, kind: str):
    """What analysing ``graph`` gives, in terms of edge positions (edges compare by identity)."""
    try:
        result = analyse(graph, kind)
    except SdfError as err:
        return type(err).__name__, str(err)
    position = {id(e): i for i, e in enumerate(graph.edges)}
    assert result.graph is graph
    return (result.repetitions, result.schedule, result.method, result.buffer_total,
            [(position[id(e)], size) for e, size in result.buffers],
            [(position[id(e)], size) for e, size in result.self_loops],
            result.sas_lower_bound, result.edge_lower_bound, result.flat_sas_total,
            result.single_appearance, result.optimal)


@SETTINGS
@given(consistent_graphs(max_actors=12, cyclic=True, delays="random"), st.sampled_from(["sas", "flat", "min-buffer"]))
def test_a_remembered_analysis_is_analyze_s_on_the_new_graph(graph, kind):
    cache = AnalysisCache()
    first = outcome(graph, cache.analyze, kind)
    assert first == outcome(graph, analyze, kind)
    again = rebuilt(graph, "moved")
    assert outcome(again, cache.analyze, kind) == outcome(again, analyze, kind) == first
    failed = isinstance(first[0], str)
    # a success is remembered, an error is not (it carries the old graph's edges)
    assert (cache.analyses, cache.hits) == ((2, 0) if failed else (1, 1))


def test_distinct_graphs_and_kinds_are_analysed_apart_and_the_oldest_forgotten():
    cache = AnalysisCache(max_entries=2)
    chain = SdfGraph(["a", "b"], [SdfEdge("a", "b", 2, 3)], name="g")
    other_rate = SdfGraph(["a", "b"], [SdfEdge("a", "b", 2, 1)], name="g")
    renamed = SdfGraph(["a", "b"], [SdfEdge("a", "b", 2, 3)], name="h")
    for g in (chain, other_rate, renamed):
        cache.analyze(g)
    assert (cache.analyses, cache.hits) == (3, 0)
    cache.analyze(rebuilt(renamed, "x"))
    cache.analyze(chain, "flat")
    assert (cache.analyses, cache.hits) == (4, 1)
    cache.analyze(rebuilt(chain, "y"))  # "sas" of the first graph: forgotten past two entries
    assert (cache.analyses, cache.hits) == (5, 1)
