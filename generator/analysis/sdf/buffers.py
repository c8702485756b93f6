"""Buffer sizes of a schedule by simulation, verification, and lower bounds.

Buffer model: non-shared buffers, one per edge; a firing takes its input
tokens at its start and delivers its output tokens at its end, so an edge's
buffer must hold the largest number of tokens it ever carries between
firings.  Simulation never unrolls loops: each subtree is summarised per edge
by its net token change and its lowest and highest level relative to its
start, and a loop of ``n`` iterations shifts those by ``(n - 1) * change``.
The cost is linear in the size of the tree, not in the number of firings.
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

from ._indexed import IndexedGraph
from .errors import ScheduleError
from .graph import SdfEdge, SdfGraph
from .repetitions import compute_repetitions
from .schedule import Fire, Schedule


class _Summary:
    """Per open edge: token change, lowest and highest level relative to the
    start of the subtree; and how many firing nodes of each actor it holds."""

    __slots__ = ("change", "low", "high", "appearances")

    def __init__(self) -> None:
        self.change: dict[int, int] = {}
        self.low: dict[int, int] = {}
        self.high: dict[int, int] = {}
        self.appearances: dict[int, int] = {}

    def _extend(self, e: int, low: int, high: int, change: int) -> None:
        # Append a segment whose levels relative to its own start are given.
        before = self.change.get(e, 0)
        self.low[e] = min(self.low.get(e, 0), before + low)
        self.high[e] = max(self.high.get(e, 0), before + high)
        self.change[e] = before + change

    def fire(self, ig: IndexedGraph, a: int, count: int) -> None:
        # _extend for the inputs (taken at the start) and outputs (given at
        # the end), written out: this is the inner loop of every check.
        change, low, high = self.change, self.low, self.high
        for e in ig.in_edges[a]:
            before = change.get(e, 0)
            change[e] = after = before - count * ig.cons[e]
            low[e] = min(low.get(e, 0), after)
            high[e] = max(high.get(e, 0), before)
        for e in ig.out_edges[a]:
            before = change.get(e, 0)
            change[e] = after = before + count * ig.prod[e]
            low[e] = min(low.get(e, 0), before)
            high[e] = max(high.get(e, 0), after)
        for e in ig.self_loops[a]:
            # Each firing takes ``cons`` first, then returns ``prod``.
            net = ig.prod[e] - ig.cons[e]
            self._extend(e, min(0, (count - 1) * net) - ig.cons[e], max(0, count * net), count * net)
        self.appearances[a] = self.appearances.get(a, 0) + 1

    def append(self, later: "_Summary") -> None:
        for e, change in later.change.items():
            self._extend(e, later.low[e], later.high[e], change)
        for a, count in later.appearances.items():
            self.appearances[a] = self.appearances.get(a, 0) + count

    def repeat(self, count: int) -> None:
        for e, change in self.change.items():
            drift = (count - 1) * change
            self.low[e] += min(0, drift)
            self.high[e] += max(0, drift)
            self.change[e] = count * change


def _edge_levels(ig: IndexedGraph, schedule: Schedule) -> dict[int, tuple[int, int, int]]:
    """Per touched edge: (change, low, high) over the whole schedule.

    Post-order over the tree with an explicit stack.  An edge is *closed* in
    a subtree that holds every firing node of both its actors: nothing else
    touches it, so its extremes are final there and it is dropped from the
    summaries above.  On a single-appearance schedule every edge travels up
    only to the loop enclosing both its actors, which keeps deep nestings
    linear.
    """
    total_appearances: dict[int, int] = {}
    for node in schedule.fire_nodes():
        if node.actor not in ig.index:
            raise ScheduleError(f"the schedule fires unknown actor {node.actor!r}")
        a = ig.index[node.actor]
        total_appearances[a] = total_appearances.get(a, 0) + 1

    closed: dict[int, tuple[int, int, int]] = {}

    def close_finished(summary: _Summary) -> None:
        done = [
            e for e in summary.change
            if summary.appearances.get(ig.src[e]) == total_appearances[ig.src[e]]
            and summary.appearances.get(ig.dst[e]) == total_appearances[ig.dst[e]]
        ]
        for e in done:
            closed[e] = (summary.change.pop(e), summary.low.pop(e), summary.high.pop(e))

    # Frames: [items, next index, summary so far, loop count].
    stack = [[schedule.body, 0, _Summary(), 1]]
    while True:
        frame = stack[-1]
        items, index, summary, count = frame
        if index < len(items):
            frame[1] = index + 1
            node = items[index]
            if isinstance(node, Fire):
                summary.fire(ig, ig.index[node.actor], node.count)
            else:
                stack.append([node.body, 0, _Summary(), node.count])
            continue
        stack.pop()
        summary.repeat(count)
        close_finished(summary)
        if not stack:
            return closed
        stack[-1][2].append(summary)


def check_schedule(
    ig: IndexedGraph, schedule: Schedule, repetitions: Sequence[int]
) -> list[int]:
    """Buffer size per edge index, after checking admissibility and period.

    Raises ScheduleError if an actor does not fire exactly its repetition
    count, an edge would go negative, or an edge does not return to its
    initial tokens.
    """
    levels = _edge_levels(ig, schedule)
    fired = schedule.firing_counts()
    for a, name in enumerate(ig.names):
        if fired.get(name, 0) != repetitions[a]:
            raise ScheduleError(
                f"actor {name} fires {fired.get(name, 0)} times, but one iteration fires it "
                f"{repetitions[a]} times"
            )
    sizes = []
    for e, edge in enumerate(ig.edges):
        change, low, high = levels.get(e, (0, 0, 0))
        if ig.delay[e] + low < 0:
            raise ScheduleError(
                f"edge {edge.describe()} would need {-(ig.delay[e] + low)} more tokens than it has: "
                f"{edge.dst} fires before {edge.src} has produced enough",
                [edge],
            )
        if change:
            raise ScheduleError(
                f"edge {edge.describe()} ends the iteration with "
                f"{ig.delay[e] + change} tokens instead of {ig.delay[e]}",
                [edge],
            )
        sizes.append(ig.delay[e] + high)
    return sizes


def verify(
    graph: SdfGraph,
    schedule: Schedule,
    buffers: Mapping[SdfEdge, int] | None = None,
) -> dict[SdfEdge, int]:
    """Check that ``schedule`` is one admissible, periodic iteration.

    Every actor must fire exactly its repetition count, no edge may go
    negative, and every edge must end with its initial tokens.  When
    ``buffers`` is given, no edge may exceed its size there.  Returns the
    buffer size each edge needs (self-loops included); raises ScheduleError.
    """
    ig = IndexedGraph.from_graph(graph)
    sizes = check_schedule(ig, schedule, compute_repetitions(ig))
    result = dict(zip(ig.edges, sizes))
    if buffers is not None:
        for edge, size in result.items():
            if edge in buffers and size > buffers[edge]:
                raise ScheduleError(
                    f"edge {edge.describe()} holds up to {size} tokens, "
                    f"more than its buffer of {buffers[edge]}",
                    [edge],
                )
    return result


def sas_edge_bound(prod: int, cons: int, delay: int) -> int:
    """Least buffer any single-appearance schedule needs on one edge.

    BMLB of Bhattacharyya, Murthy & Lee: ``eta = prod * cons / gcd`` for a
    delayless edge; with ``delay`` tokens, ``eta + delay`` if ``delay < eta``,
    else ``delay``.
    """
    eta = prod * cons // math.gcd(prod, cons)
    return eta + delay if delay < eta else delay


def min_edge_bound(prod: int, cons: int, delay: int) -> int:
    """Least buffer any schedule needs on one edge (two-actor optimum).

    ``prod + cons - g + delay mod g`` with ``g = gcd(prod, cons)`` when
    ``delay <= prod + cons - g``, else ``delay``.
    """
    g = math.gcd(prod, cons)
    if delay <= prod + cons - g:
        return prod + cons - g + delay % g
    return delay


def sas_lower_bound(graph: SdfGraph) -> int:
    """Sum of :func:`sas_edge_bound` over the edges that are not self-loops."""
    return sum(
        sas_edge_bound(e.prod, e.cons, e.delay) for e in graph.edges if not e.is_self_loop
    )


def edge_lower_bound(graph: SdfGraph) -> int:
    """Sum of :func:`min_edge_bound` over the edges that are not self-loops."""
    return sum(
        min_edge_bound(e.prod, e.cons, e.delay) for e in graph.edges if not e.is_self_loop
    )
