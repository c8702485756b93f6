"""Remembering analyses across calls, for a caller that analyses the same
graphs again and again (the language server, after every edit).

:func:`analyze` is a pure function of the graph's actors and edges (their
names, rates and delays), the graph's name, the schedule kind and the
options; an edge's ``loc`` is opaque to it and only reaches errors. So an
analysis found for an equal graph is the analysis of the new one, once
its edges are those of the new graph: :meth:`AnalysisCache.analyze` hands
it back rebound, edge for edge in graph order, so that the result's edges
are the new graph's objects (edges compare by identity) with their own
``loc``. Errors are not remembered: they carry the edges of the graph
that raised them, and a graph without a schedule fails fast anyway.
"""

from __future__ import annotations

import dataclasses
from collections import OrderedDict
from collections.abc import Hashable

from .analysis import Analysis, analyze
from .graph import SdfGraph
from .options import SdfOptions

# Every dataflow of a large model (the 5,000-actor benchmark has 100) in
# several versions; the least recently used analyses go first beyond it.
# Each entry keeps its graph and schedule alive: a few hundred objects.
DEFAULT_MAX_ENTRIES = 1024


def graph_key(graph: SdfGraph, schedule: str, options: SdfOptions | None) -> Hashable:
    """Everything :func:`analyze` reads of its arguments, as one hashable value."""
    edges = tuple((e.src, e.dst, e.prod, e.cons, e.delay, e.name) for e in graph.edges)
    return (schedule, options or SdfOptions(), graph.name, graph.actors, edges)


def rebind(found: Analysis, graph: SdfGraph) -> Analysis:
    """``found`` (the analysis of a graph equal to ``graph``) with ``graph``'s
    own edge objects in place of the old graph's."""
    new_edge = {id(old): new for old, new in zip(found.graph.edges, graph.edges)}
    return dataclasses.replace(
        found, graph=graph, repetitions=dict(found.repetitions),
        buffers=[(new_edge[id(e)], size) for e, size in found.buffers],
        self_loops=[(new_edge[id(e)], size) for e, size in found.self_loops])


class AnalysisCache:
    """:func:`analyze` with its results remembered by :func:`graph_key`.

    ``analyses`` counts the calls that really analysed a graph, ``hits``
    those answered from memory (tests and the benchmark read them).
    """

    def __init__(self, max_entries: int = DEFAULT_MAX_ENTRIES) -> None:
        self.max_entries = max_entries
        self._found: OrderedDict[Hashable, Analysis] = OrderedDict()
        self.analyses = 0
        self.hits = 0

    def analyze(self, graph: SdfGraph, schedule: str = "sas", options: SdfOptions | None = None) -> Analysis:
        """What :func:`analyze` gives for these arguments (and raises the same errors)."""
        key = graph_key(graph, schedule, options)
        found = self._found.get(key)
        if found is not None:
            self._found.move_to_end(key)
            self.hits += 1
            return rebind(found, graph)
        self.analyses += 1
        result = analyze(graph, schedule, options)
        self._found[key] = result
        if len(self._found) > self.max_entries:
            self._found.popitem(last=False)
        return result
