"""Lexical orders for single-appearance schedules of an acyclic graph.

Both heuristics of Bhattacharyya, Murthy & Lee (1996) are here, each
returning a lexical order with a nesting (see ``dppo``) that DPPO then
improves:

* APGAN, acyclic pairwise grouping of adjacent nodes: repeatedly merge the
  adjacent pair with the largest gcd of repetition counts whose merge keeps
  the graph acyclic.  With a lazily updated heap of pairs and small-into-large
  merging it runs in O(E log E) plus the acyclicity searches, which are
  bounded (see :func:`apgan`), so it scales to 10,000 actors.
* RPMC, recursive partitioning by minimum cuts: split the nodes in two, all
  precedence edges crossing forwards, so that the traffic crossing is least
  while each side keeps between a quarter and three quarters of the nodes;
  recurse on both sides.  Our cut search (a documented simplification) tries
  every prefix of two topological orders of the part at hand, Kahn's
  breadth-first one and a depth-first one; each level costs linear time, so
  RPMC scales to 10,000 actors.

The graph handed in is a :class:`LevelDag`: nodes with repetition counts,
precedence edges (acyclic), and edges without precedence (their delay covers
a whole iteration, so they may run either way).
"""

from __future__ import annotations

import heapq
import math
from itertools import accumulate
from operator import add, neg
from typing import Sequence

from ._digraph import depth_first_topological_order, topological_order
from .dppo import Splits


class LevelDag:
    """An acyclic graph of nodes with repetition counts and traffic.

    ``edges`` are ``(u, v, traffic, precedence)``: ``traffic`` tokens per
    iteration flow from ``u`` to ``v``; only edges with ``precedence`` order
    the nodes.  ``priority`` breaks ties (lower first) deterministically.
    """

    def __init__(
        self,
        counts: Sequence[int],
        priority: Sequence[int],
        edges: Sequence[tuple[int, int, int, bool]],
    ) -> None:
        self.counts = list(counts)
        self.priority = list(priority)
        self.edges = list(edges)
        self.size = len(self.counts)
        self.traffic_out: list[list[tuple[int, int]]] = [[] for _ in range(self.size)]
        successor_sets: list[dict[int, None]] = [{} for _ in range(self.size)]
        for u, v, traffic, precedence in self.edges:
            self.traffic_out[u].append((v, traffic))
            if precedence:
                successor_sets[u][v] = None
        self.succ = [list(s) for s in successor_sets]

    def traffic_edges(self) -> list[tuple[int, int, int]]:
        """All edges as ``(u, v, traffic)``."""
        return [(u, v, traffic) for u, v, traffic, _ in self.edges]

    def topological_order(self) -> list[int]:
        """Kahn's order, lowest priority first among ready nodes."""
        order = topological_order(range(self.size), self.succ, self.priority)
        if order is None:
            raise AssertionError("a level graph must be acyclic")
        return order


def bisection(dag: LevelDag, order: Sequence[int], reorder: bool) -> tuple[list[int], Splits]:
    """Recursive minimum-cut bisection; returns the lexical order and nesting.

    With ``reorder`` each part is re-sorted topologically before it is cut
    (RPMC); without, the cuts are the prefixes of ``order`` and the lexical
    order stays ``order``.
    """
    size = len(order)
    final = list(order)
    splits: Splits = {}
    if size < 2:
        return final, splits
    # Parts to cut: the part, its first position, and its candidate orders
    # when known already.
    pending: list[tuple[list[int], int, list[list[int]] | None]] = [(list(order), 0, None)]
    while pending:
        part, lo, candidates = pending.pop()
        if len(part) == 1:
            final[lo] = part[0]
            continue
        if not reorder:
            candidates = [part]
        elif candidates is None:
            kahn = topological_order(part, dag.succ, dag.priority)
            candidates = [kahn]
            # A part whose order is a path of edges has no other order to try.
            if not all(b in dag.succ[a] for a, b in zip(kahn, kahn[1:])):
                candidates.append(
                    depth_first_topological_order(sorted(part, key=dag.priority.__getitem__), dag.succ))
        best_key, best_sequence, best_cut = None, None, 0
        for sequence in candidates:
            if sequence == best_sequence:
                continue  # the same order (often, in small parts) has the same cut
            key, cut = _best_prefix_cut(dag, sequence)
            if best_key is None or key < best_key:
                best_key, best_sequence, best_cut = key, sequence, cut
        splits[(lo, lo + len(part) - 1)] = lo + best_cut
        left, right = best_sequence[:best_cut + 1], best_sequence[best_cut + 1:]
        left_orders = None
        if reorder:
            # The left part is a prefix of a topological order of the part: no
            # edge enters it from the rest of the part, so its Kahn order and
            # its depth-first order are the part's, restricted to it.
            inside = set(left).__contains__
            left_orders = [left if o is best_sequence else list(filter(inside, o)) for o in candidates]
        pending.append((right, lo + best_cut + 1, None))
        pending.append((left, lo, left_orders))
    return final, splits


def _best_prefix_cut(dag: LevelDag, sequence: list[int]) -> tuple[tuple[int, int, int], int]:
    """Best cut after position ``cut`` of ``sequence``: (ranking key, cut)."""
    size = len(sequence)
    if size == 2:  # the only cut, ranked as below (the most frequent part by far)
        a, b = sequence
        return (sum(traffic for v, traffic in dag.traffic_out[a] if v == b), -(dag.counts[a] + dag.counts[b]), 0), 0
    position = dict(zip(sequence, range(size)))  # inside the part
    # Traffic crossing the cut after position t, by a difference array.
    change = [0] * (size + 1)
    traffic_out = dag.traffic_out
    for a, node in enumerate(sequence):
        for v, traffic in traffic_out[node]:
            b = position.get(v, -1)
            if b > a:
                change[a] += traffic
                change[b] -= traffic
    counts = list(map(dag.counts.__getitem__, sequence))
    prefix_gcd = list(accumulate(counts, math.gcd))
    suffix_gcd = list(accumulate(reversed(counts), math.gcd))[::-1]
    # Each side keeps at least a quarter of the nodes: recursion depth stays
    # logarithmic. Cuts after lo .. hi - 1 qualify.
    smallest = (size + 3) // 4 if size >= 4 else 1
    lo, hi = smallest - 1, size - smallest
    # Least traffic; then the larger loop factors inside the two parts;
    # then the more even split; then the first.
    crossing = list(accumulate(change[:hi]))
    key = min(zip(
        crossing[lo:],
        map(neg, map(add, prefix_gcd[lo:hi], suffix_gcd[lo + 1:hi + 1])),
        map(abs, range(size - 2 * (lo + 1), size - 2 * (hi + 1), -2)),
        range(lo, hi),
    ))
    return key[:3], key[3]


def apgan(dag: LevelDag, search_limit: int) -> tuple[list[int], Splits]:
    """APGAN's lexical order and the nesting its clustering implies.

    Candidate pairs (precedence-adjacent clusters) sit in a heap ranked by
    the gcd of their counts, then the traffic between them, then priority;
    entries are re-ranked lazily when popped, since merges only ever lower a
    pair's gcd.  A merge keeps the id of the cluster with more neighbours and
    moves the other's adjacency over (small into large), so merging costs
    the smaller degree.  Whether a merge would close a cycle is a search
    for another path; it gives up beyond ``search_limit`` nodes and then
    conservatively skips the pair (exact on graphs of up to that many
    nodes).
    """
    if dag.size < 2:
        return list(range(dag.size)), {}
    count = list(dag.counts)
    priority = list(dag.priority)
    tree: list[object] = list(range(dag.size))   # int leaf or (left, right)
    succ = [set(s) for s in dag.succ]
    pred: list[set[int]] = [set() for _ in range(dag.size)]
    for u, successors in enumerate(dag.succ):
        for v in successors:
            pred[v].add(u)
    traffic: dict[tuple[int, int], int] = {}
    for u, v, w, precedence in dag.edges:
        if precedence:
            traffic[(u, v)] = traffic.get((u, v), 0) + w
    alive = [True] * dag.size

    def rank(u: int, v: int) -> tuple[int, int, int, int, int]:
        return (-math.gcd(count[u], count[v]), -traffic.get((u, v), 0),
                min(priority[u], priority[v]), u, v)

    heap = [rank(u, v) for u in range(dag.size) for v in succ[u]]
    heapq.heapify(heap)
    while heap:
        entry = heapq.heappop(heap)
        u, v = entry[3], entry[4]
        if not (alive[u] and alive[v] and v in succ[u]):
            continue
        current = rank(u, v)
        if current != entry:
            heapq.heappush(heap, current)
            continue
        if _other_path(succ, pred, u, v, search_limit):
            # Stays invalid until a cluster on the other path merges into
            # u or v, and such a merge pushes the pair again.
            continue
        succ[u].discard(v)
        pred[v].discard(u)
        traffic.pop((u, v), None)
        big, small = (u, v) if len(succ[u]) + len(pred[u]) >= len(succ[v]) + len(pred[v]) else (v, u)
        for x in succ[small]:
            pred[x].discard(small)
            pred[x].add(big)
            succ[big].add(x)
            traffic[(big, x)] = traffic.get((big, x), 0) + traffic.pop((small, x), 0)
        for x in pred[small]:
            succ[x].discard(small)
            succ[x].add(big)
            pred[big].add(x)
            traffic[(x, big)] = traffic.get((x, big), 0) + traffic.pop((x, small), 0)
        count[big] = math.gcd(count[u], count[v])
        priority[big] = min(priority[u], priority[v])
        tree[big] = (tree[u], tree[v])
        alive[small] = False
        moved_succ, moved_pred = succ[small], pred[small]
        succ[small] = pred[small] = set()
        for x in moved_succ:
            heapq.heappush(heap, rank(big, x))
        for x in moved_pred:
            heapq.heappush(heap, rank(x, big))

    # Clusters left over (none on fully searched graphs) in topological order.
    roots = [c for c in range(dag.size) if alive[c]]
    order = topological_order(roots, [sorted(s) for s in succ], priority)
    top = tree[order[0]]
    for root in order[1:]:
        top = (top, tree[root])
    return _layout(top)


def _other_path(succ: list[set[int]], pred: list[set[int]], u: int, v: int, limit: int) -> bool:
    """Whether ``v`` is reachable from ``u`` other than by the direct edge.

    Answers True (unsafe) when the nodes reachable from ``u``'s other
    successors are more than ``limit`` (or than those successors): the
    answer depends on the reachable set only, not on the order of the
    search, which goes breadth-first with set operations.
    """
    if len(succ[u]) == 1 or len(pred[v]) == 1:
        return False   # any other path would need another edge out of u / into v
    seen = succ[u] - {v}
    bound = max(limit, len(seen))
    frontier = seen
    while frontier:
        reached = set().union(*map(succ.__getitem__, frontier))
        if v in reached:
            return True
        frontier = reached - seen
        seen = seen | frontier
        if len(seen) > bound:
            return True
    return False


def _layout(tree: object) -> tuple[list[int], Splits]:
    """In-order leaves of a binary tree of tuples, and its ranges' splits."""
    order: list[int] = []
    splits: Splits = {}
    spans: list[tuple[int, int]] = []
    stack: list[tuple[object, bool]] = [(tree, False)]
    while stack:
        node, children_done = stack.pop()
        if isinstance(node, int):
            spans.append((len(order), len(order)))
            order.append(node)
        elif not children_done:
            stack.append((node, True))
            stack.append((node[1], False))
            stack.append((node[0], False))
        else:
            right = spans.pop()
            left = spans.pop()
            splits[(left[0], right[1])] = left[1]
            spans.append((left[0], right[1]))
    return order, splits
