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

    # Rates as reduced fractions num/den (plain integers: far cheaper than
    # Fraction objects on graphs of 10,000 actors); 0 until reached.
    num = [0] * ig.actor_count
    den = [1] * ig.actor_count
    parent_edge = [-1] * ig.actor_count
    depth = [0] * ig.actor_count
    repetitions = [0] * ig.actor_count
    src, dst, prod, cons = ig.src, ig.dst, ig.prod, ig.cons
    for members in weakly_connected_components(ig):
        root = members[0]
        num[root] = 1
        queue = deque([root])
        while queue:
            v = queue.popleft()
            for e, w in incident[v]:
                if num[w] == 0:
                    # Balance: q[dst] = q[src] * prod / cons.
                    if src[e] == v:
                        n, d = num[v] * prod[e], den[v] * cons[e]
                    else:
                        n, d = num[v] * cons[e], den[v] * prod[e]
                    g = math.gcd(n, d)
                    num[w], den[w] = n // g, d // g
                    parent_edge[w] = e
                    depth[w] = depth[v] + 1
                    queue.append(w)
        for v in members:
            for e, _ in incident[v]:
                w = dst[e]
                if src[e] == v and num[v] * prod[e] * den[w] != num[w] * cons[e] * den[v]:
                    cycle = _tree_cycle(ig, e, parent_edge, depth)
                    raise _inconsistency(ig, cycle, src[e])
        scale = math.lcm(*(den[v] for v in members))
        integers = [num[v] * (scale // den[v]) for v in members]
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
