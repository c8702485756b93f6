"""Balance equations: the repetition vector of a consistent SDF graph.

For every edge ``q[src] * prod == q[dst] * cons``.  We solve per weakly
connected component by propagating exact rationals over a breadth-first
spanning tree, check every edge, then scale to the smallest positive integer
solution (gcd 1 per component).
"""

from __future__ import annotations

import math
from collections import deque
from fractions import Fraction

from ._indexed import IndexedGraph
from .errors import InconsistentGraphError
from .graph import SdfGraph


def weakly_connected_components(ig: IndexedGraph) -> list[list[int]]:
    """Actor sets connected by edges in either direction, in actor order."""
    neighbours: list[list[int]] = [[] for _ in range(ig.actor_count)]
    for s, d in zip(ig.src, ig.dst):
        if s != d:
            neighbours[s].append(d)
            neighbours[d].append(s)
    component_of = [-1] * ig.actor_count
    components: list[list[int]] = []
    for root in range(ig.actor_count):
        if component_of[root] >= 0:
            continue
        component_of[root] = len(components)
        members = [root]
        queue = deque([root])
        while queue:
            v = queue.popleft()
            for w in neighbours[v]:
                if component_of[w] < 0:
                    component_of[w] = len(components)
                    members.append(w)
                    queue.append(w)
        members.sort()
        components.append(members)
    return components


def compute_repetitions(ig: IndexedGraph) -> list[int]:
    """The repetition vector by actor index; raises InconsistentGraphError."""
    for e in range(ig.edge_count):
        if ig.is_self_loop(e) and ig.prod[e] != ig.cons[e]:
            raise _inconsistency(ig, [e], ig.src[e])

    # Undirected adjacency: (edge, neighbour) pairs.
    incident: list[list[tuple[int, int]]] = [[] for _ in range(ig.actor_count)]
    for e, (s, d) in enumerate(zip(ig.src, ig.dst)):
        if s != d:
            incident[s].append((e, d))
            incident[d].append((e, s))

    rate: list[Fraction | None] = [None] * ig.actor_count
    parent_edge = [-1] * ig.actor_count
    depth = [0] * ig.actor_count
    repetitions = [0] * ig.actor_count
    for members in weakly_connected_components(ig):
        root = members[0]
        rate[root] = Fraction(1)
        queue = deque([root])
        while queue:
            v = queue.popleft()
            for e, w in incident[v]:
                if rate[w] is None:
                    # Balance: q[dst] = q[src] * prod / cons.
                    if ig.src[e] == v:
                        rate[w] = rate[v] * ig.prod[e] / ig.cons[e]
                    else:
                        rate[w] = rate[v] * ig.cons[e] / ig.prod[e]
                    parent_edge[w] = e
                    depth[w] = depth[v] + 1
                    queue.append(w)
        for v in members:
            for e, _ in incident[v]:
                if ig.src[e] == v and rate[v] * ig.prod[e] != rate[ig.dst[e]] * ig.cons[e]:
                    cycle = _tree_cycle(ig, e, parent_edge, depth)
                    raise _inconsistency(ig, cycle, ig.src[e])
        scale = math.lcm(*(rate[v].denominator for v in members))
        integers = [int(rate[v] * scale) for v in members]
        divisor = math.gcd(*integers)
        for v, value in zip(members, integers):
            repetitions[v] = value // divisor
    return repetitions


def repetition_vector(graph: SdfGraph) -> dict[str, int]:
    """Smallest positive integer solution of the balance equations.

    Returns ``{actor: firings per iteration}`` in actor order, with gcd 1 in
    every weakly connected component; raises InconsistentGraphError.
    """
    ig = IndexedGraph.from_graph(graph)
    return dict(zip(ig.names, compute_repetitions(ig)))


def _tree_cycle(ig: IndexedGraph, closing: int, parent_edge: list[int], depth: list[int]) -> list[int]:
    """The closing edge followed by the tree path from its dst back to its src."""
    def up(v: int) -> int:
        e = parent_edge[v]
        return ig.src[e] if ig.dst[e] == v else ig.dst[e]

    u, v = ig.src[closing], ig.dst[closing]
    from_v: list[int] = []   # edges from v up to the common ancestor
    from_u: list[int] = []   # edges from u up to the common ancestor
    while depth[v] > depth[u]:
        from_v.append(parent_edge[v])
        v = up(v)
    while depth[u] > depth[v]:
        from_u.append(parent_edge[u])
        u = up(u)
    while u != v:
        from_v.append(parent_edge[v])
        v = up(v)
        from_u.append(parent_edge[u])
        u = up(u)
    return [closing] + from_v + from_u[::-1]


def cycle_gain(ig: IndexedGraph, cycle: list[int], start: int) -> Fraction:
    """Ratio q[start]'/q[start] obtained by propagating rates round ``cycle``.

    The cycle is walked as an undirected closed walk from actor ``start``;
    a consistent cycle has gain 1.
    """
    gain = Fraction(1)
    at = start
    for e in cycle:
        if ig.src[e] == at:
            gain = gain * ig.prod[e] / ig.cons[e]
            at = ig.dst[e]
        else:
            gain = gain * ig.cons[e] / ig.prod[e]
            at = ig.src[e]
    return gain


def _inconsistency(ig: IndexedGraph, cycle: list[int], start: int) -> InconsistentGraphError:
    gain = cycle_gain(ig, cycle, start)
    lines = "\n".join(f"  {ig.edges[e].describe()}" for e in cycle)
    actor = ig.names[start]
    message = (
        "inconsistent sample rates: the balance equations "
        "(q[src] * produced = q[dst] * consumed) have no positive solution on this cycle:\n"
        f"{lines}\n"
        f"going round it from {actor}, {actor} would have to fire {gain} times "
        "as often as itself"
    )
    return InconsistentGraphError(message, [ig.edges[e] for e in cycle])
