"""Plain directed-graph algorithms on adjacency lists, all iterative.

Graphs here are ``succ[v] = [w, ...]`` over nodes ``0..n-1`` (or a subset
given explicitly).  No recursion: SDF graphs of 10,000 actors in a chain
would overflow Python's stack.
"""

from __future__ import annotations

import heapq
from collections import Counter
from itertools import chain
from typing import Sequence


def strongly_connected_components(
    nodes: Sequence[int], succ: Sequence[Sequence[int]]
) -> list[list[int]]:
    """Tarjan's algorithm; components come in topological order.

    Only successors inside ``nodes`` are followed.  Within a component, nodes
    keep the order of ``nodes``.
    """
    position = {v: i for i, v in enumerate(nodes)}
    index: dict[int, int] = {}
    lowlink: dict[int, int] = {}
    on_stack: set[int] = set()
    stack: list[int] = []
    components: list[list[int]] = []
    counter = 0
    for root in nodes:
        if root in index:
            continue
        # Each frame is (node, iterator position into its successor list).
        frames = [(root, 0)]
        index[root] = lowlink[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while frames:
            v, i = frames[-1]
            successors = succ[v]
            if i < len(successors):
                frames[-1] = (v, i + 1)
                w = successors[i]
                if w not in position:
                    continue
                if w not in index:
                    index[w] = lowlink[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    frames.append((w, 0))
                elif w in on_stack:
                    lowlink[v] = min(lowlink[v], index[w])
                continue
            frames.pop()
            if frames:
                parent = frames[-1][0]
                lowlink[parent] = min(lowlink[parent], lowlink[v])
            if lowlink[v] == index[v]:
                component = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    component.append(w)
                    if w == v:
                        break
                component.sort(key=position.__getitem__)
                components.append(component)
    # Tarjan finishes sink components first.
    components.reverse()
    return components


def topological_order(
    nodes: Sequence[int], succ: Sequence[Sequence[int]], priority: Sequence[int] | None = None
) -> list[int] | None:
    """Kahn's algorithm, always taking the ready node of smallest priority.

    ``priority`` (integers) defaults to the node number.  Returns None on a
    cycle.
    """
    members = set(nodes)
    inside = members.__contains__
    # In-degrees inside ``nodes``, counted without a Python loop per edge.
    indegree = dict.fromkeys(members, 0)
    indegree.update(Counter(filter(inside, chain.from_iterable(map(succ.__getitem__, members)))))
    # The heap holds key * scale + node: the order of (key, node) pairs,
    # without a tuple per entry.
    scale = max(nodes, default=0) + 1
    key = priority if priority is not None else range(scale)
    ready = [key[v] * scale + v for v in nodes if not indegree[v]]
    heapq.heapify(ready)
    order = []
    while ready:
        v = heapq.heappop(ready) % scale
        order.append(v)
        for w in filter(inside, succ[v]):
            left = indegree[w] - 1
            indegree[w] = left
            if not left:
                heapq.heappush(ready, key[w] * scale + w)
    return order if len(order) == len(indegree) else None


def depth_first_topological_order(
    nodes: Sequence[int], succ: Sequence[Sequence[int]]
) -> list[int]:
    """Reverse postorder of a depth-first search (the nodes must form a DAG).

    Unlike Kahn's breadth-first order it keeps each path together, which gives
    the partitioning heuristics different cuts to choose from.
    """
    members = set(nodes)
    visited: set[int] = set()
    postorder: list[int] = []
    for root in nodes:
        if root in visited:
            continue
        visited.add(root)
        # Each frame is a node and the iterator over its successors.
        frames = [(root, iter(succ[root]))]
        while frames:
            v, successors = frames[-1]
            for w in successors:
                if w in members and w not in visited:
                    visited.add(w)
                    frames.append((w, iter(succ[w])))
                    break
            else:
                frames.pop()
                postorder.append(v)
    postorder.reverse()
    return postorder
