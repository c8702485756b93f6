"""Integer-indexed view of an SDF graph, the form every algorithm works on.

Actors become 0..n-1 in graph order, edges 0..m-1 in graph order; rates live
in flat lists so the inner loops index lists instead of chasing attributes.
Self-loops are kept apart from the ordinary in/out adjacency because they
never order two actors and never limit how often an actor fires in a row.
"""

from __future__ import annotations

from typing import Sequence

from .graph import SdfEdge, SdfGraph


class IndexedGraph:
    """Actors, edges and adjacency as index lists; built once per analysis."""

    __slots__ = (
        "names", "index", "edges", "src", "dst", "prod", "cons", "delay",
        "out_edges", "in_edges", "self_loops",
    )

    def __init__(self, names: Sequence[str], edges: Sequence[SdfEdge]) -> None:
        self.names = list(names)
        self.index = {name: i for i, name in enumerate(self.names)}
        self.edges = list(edges)
        self.src = [self.index[e.src] for e in self.edges]
        self.dst = [self.index[e.dst] for e in self.edges]
        self.prod = [e.prod for e in self.edges]
        self.cons = [e.cons for e in self.edges]
        self.delay = [e.delay for e in self.edges]
        count = len(self.names)
        self.out_edges: list[list[int]] = [[] for _ in range(count)]
        self.in_edges: list[list[int]] = [[] for _ in range(count)]
        self.self_loops: list[list[int]] = [[] for _ in range(count)]
        for e, (s, d) in enumerate(zip(self.src, self.dst)):
            if s == d:
                self.self_loops[s].append(e)
            else:
                self.out_edges[s].append(e)
                self.in_edges[d].append(e)

    @classmethod
    def from_graph(cls, graph: SdfGraph) -> "IndexedGraph":
        return cls(graph.actors, graph.edges)

    @property
    def actor_count(self) -> int:
        return len(self.names)

    @property
    def edge_count(self) -> int:
        return len(self.edges)

    def is_self_loop(self, e: int) -> bool:
        return self.src[e] == self.dst[e]

    def subgraph(self, actors: Sequence[int], edges: Sequence[int]) -> "IndexedGraph":
        """The graph on ``actors`` (in the given order) with ``edges`` only."""
        return IndexedGraph([self.names[a] for a in actors], [self.edges[e] for e in edges])
