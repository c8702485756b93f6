"""Loop nesting for a fixed lexical order: DPPO and what it works on.

A *nesting* of a lexical order ``order[0..m-1]`` is a binary bracketing,
stored as ``splits[(lo, hi)] = k``: the range ``lo..hi`` runs as a loop of
``g(lo, hi)`` iterations (``g`` the gcd of the counts of its nodes) over the
part ``lo..k`` followed by the part ``k+1..hi``.  Under the non-shared buffer
model an edge from position ``a`` to ``b > a`` then needs its delay plus
``w / g`` tokens of buffer (``w`` its traffic per iteration) where ``lo..hi``
is the range whose split separates ``a`` from ``b``; an edge running
backwards (possible only for an edge whose delay covers the whole traffic)
needs just its delay.

DPPO (Bhattacharyya, Murthy & Lee 1996) finds the cheapest nesting by
dynamic programming over all ranges in O(m^3) time and O(m^2) space.
"""

from __future__ import annotations

import math
from itertools import accumulate
from typing import Callable, Sequence

from .schedule import Node, repeat

Splits = dict[tuple[int, int], int]


class SparseTable:
    """Any range ``lo..hi`` of a list folded by an idempotent ``combine``, in O(1).

    Overlapping halves are fine because ``combine(x, x) == x`` (gcd, min).
    """

    def __init__(self, values: Sequence, combine: Callable) -> None:
        self._combine = combine
        self._levels = [list(values)]
        width = 1
        while 2 * width <= len(values):
            previous = self._levels[-1]
            # combine(previous[i], previous[i + width]) for every i that fits
            self._levels.append(list(map(combine, previous, previous[width:])))
            width *= 2

    def __call__(self, lo: int, hi: int):
        level = (hi - lo + 1).bit_length() - 1
        row = self._levels[level]
        return self._combine(row[lo], row[hi - (1 << level) + 1])


def range_gcd(values: Sequence[int]) -> SparseTable:
    """gcd of any range of ``values`` in O(1)."""
    return SparseTable(values, math.gcd)


def dppo(counts: Sequence[int], edges: Sequence[tuple[int, int, int]]) -> tuple[int, Splits]:
    """Cheapest nesting of ``counts`` (positions 0..m-1) and its cost.

    ``edges`` are ``(a, b, w)`` with ``a < b``: traffic ``w`` from position
    ``a`` to ``b``.  Backward edges cost the same in every nesting, so the
    caller leaves them out.
    """
    m = len(counts)
    if m < 2:
        return 0, {}
    # out_prefix[a][t]: traffic from a to positions < t; in_prefix[b][t]:
    # traffic into b from positions < t.  They make the traffic across a
    # split an O(1) update when the split point moves by one.
    out_prefix = [[0] * (m + 1) for _ in range(m)]
    in_prefix = [[0] * (m + 1) for _ in range(m)]
    for a, b, w in edges:
        out_prefix[a][b + 1] += w
        in_prefix[b][a + 1] += w
    out_prefix = [list(accumulate(row)) for row in out_prefix]
    in_prefix = [list(accumulate(row)) for row in in_prefix]
    gcds = [list(accumulate(counts[i:], math.gcd)) for i in range(m)]  # gcds[i][j - i]: of i..j

    best = [[0] * m for _ in range(m)]
    column = [[0] * m for _ in range(m)]  # column[j][k] is best[k][j]
    split = [[0] * m for _ in range(m)]
    for length in range(1, m):
        for i in range(m - length):
            j = i + length
            g = gcds[i][length]
            row_i, column_j = best[i], column[j]
            crossing = out_prefix[i][j + 1] - out_prefix[i][i + 1]
            chosen, chosen_cost = i, row_i[i] + column_j[i + 1] + crossing // g
            for k in range(i + 1, j):
                # Node k moves from the right part to the left part.
                out_k, in_k = out_prefix[k], in_prefix[k]
                crossing += out_k[j + 1] - out_k[k + 1] - in_k[k] + in_k[i]
                cost = row_i[k] + column_j[k + 1] + crossing // g
                if cost < chosen_cost:
                    chosen, chosen_cost = k, cost
            row_i[j] = column_j[i] = chosen_cost
            split[i][j] = chosen

    splits: Splits = {}
    pending = [(0, m - 1)]
    while pending:
        lo, hi = pending.pop()
        if lo < hi:
            k = split[lo][hi]
            splits[(lo, hi)] = k
            pending.append((lo, k))
            pending.append((k + 1, hi))
    return best[0][m - 1], splits


def forward_edges(
    order: Sequence[int], edges: Sequence[tuple[int, int, int]]
) -> list[tuple[int, int, int]]:
    """Node-level edges ``(u, v, w)`` as position-level forward edges."""
    position = {node: p for p, node in enumerate(order)}
    result = []
    for u, v, w in edges:
        a, b = position[u], position[v]
        if a < b:
            result.append((a, b, w))
    return result


def optimize_nesting(
    counts: Sequence[int],
    edges: Sequence[tuple[int, int, int]],
    hierarchy: Splits,
    window: int,
    solved: dict | None = None,
) -> Splits:
    """DPPO on every maximal range of ``hierarchy`` with at most ``window`` nodes.

    ``counts`` and ``edges`` are by position.  Ranges above the window keep
    the hierarchy's split, so the cost is O(m * window^2) instead of O(m^3);
    with ``window >= m`` this is plain DPPO.  Each window is solved
    optimally, so the result never costs more than ``hierarchy``.
    ``solved`` keeps the nestings found, by window (its counts and edges),
    for the next call: orders that share windows solve them once.
    """
    m = len(counts)
    if m < 2:
        return {}
    outgoing: list[list[tuple[int, int]]] = [[] for _ in range(m)]
    for a, b, w in edges:
        outgoing[a].append((b, w))
    splits: Splits = {}
    pending = [(0, m - 1)]
    while pending:
        lo, hi = pending.pop()
        if lo == hi:
            continue
        if hi - lo + 1 <= window:
            local_counts = tuple(counts[lo:hi + 1])
            local_edges = tuple(
                (a - lo, b - lo, w) for a in range(lo, hi + 1) for b, w in outgoing[a] if b <= hi
            )
            local = None if solved is None else solved.get((local_counts, local_edges))
            if local is None:
                _, local = dppo(local_counts, local_edges)
                if solved is not None:
                    solved[(local_counts, local_edges)] = local
            for (i, j), k in local.items():
                splits[(i + lo, j + lo)] = k + lo
            continue
        k = hierarchy[(lo, hi)]
        splits[(lo, hi)] = k
        pending.append((lo, k))
        pending.append((k + 1, hi))
    return splits


def nesting_cost(
    counts: Sequence[int], edges: Sequence[tuple[int, int, int]], splits: Splits
) -> int:
    """Buffer cost of forward ``edges`` (by position) under ``splits``.

    Every split point ``k`` belongs to exactly one range; an edge ``a -> b``
    is separated by the shallowest range whose split point lies in
    ``a..b-1``, found with a range-minimum query over split depths.  So the
    cost is O(m log m + edges) however deep the nesting.
    """
    m = len(counts)
    if m < 2:
        return 0
    depth = [0] * (m - 1)
    span = [(0, 0)] * (m - 1)
    pending = [(0, m - 1, 0)]
    while pending:
        lo, hi, level = pending.pop()
        if lo < hi:
            k = splits[(lo, hi)]
            depth[k], span[k] = level, (lo, hi)
            pending.append((lo, k, level + 1))
            pending.append((k + 1, hi, level + 1))
    shallowest = SparseTable(range(m - 1), lambda i, j: i if depth[i] <= depth[j] else j)
    gcd = range_gcd(counts)
    total = 0
    for a, b, w in edges:
        lo, hi = span[shallowest(a, b - 1)]
        total += w // gcd(lo, hi)
    return total


def order_lower_bound(counts: Sequence[int], edges: Sequence[tuple[int, int, int]]) -> int:
    """Least buffer cost of forward ``edges`` (by position) under any nesting
    of this order: the range whose split separates ``a`` from ``b`` holds
    ``a..b``, so its gcd divides the gcd of ``a..b``."""
    if len(counts) < 2:
        return 0
    gcd = range_gcd(counts)
    return sum(w // gcd(a, b) for a, b, w in edges)


def nested_items(
    counts: Sequence[int],
    splits: Splits,
    leaf_items: Callable[[int], list[Node]],
) -> list[Node]:
    """The schedule items of one iteration for a nesting.

    ``leaf_items(p)`` gives the items of one firing of the node at position
    ``p`` (one actor firing, or a cluster's own iteration) as a new list.  Counts must have
    gcd 1 overall, as repetition counts of one level do.
    """
    m = len(counts)
    if m == 0:
        return []
    gcd = range_gcd(counts)
    # Post-order over ranges with an explicit stack; each finished range
    # leaves (items per iteration of its own loop, its gcd) on `results`.
    results: list[tuple[list[Node], int]] = []
    stack: list[tuple[int, int, bool]] = [(0, m - 1, False)]
    while stack:
        lo, hi, children_done = stack.pop()
        if lo == hi:
            results.append((leaf_items(lo), counts[lo]))
            continue
        if not children_done:
            k = splits[(lo, hi)]
            stack.append((lo, hi, True))
            stack.append((k + 1, hi, False))
            stack.append((lo, k, False))
            continue
        right_items, right_gcd = results.pop()
        left_items, left_gcd = results.pop()
        g = gcd(lo, hi)
        # Lists on `results` are owned here, so a part that needs no loop of
        # its own is extended in place (deep nestings stay linear).
        items = left_items if left_gcd == g else repeat(left_gcd // g, left_items)
        items.extend(right_items if right_gcd == g else repeat(right_gcd // g, right_items))
        results.append((items, g))
    items, g = results.pop()
    return repeat(g, items)
