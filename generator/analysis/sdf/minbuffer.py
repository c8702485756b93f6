"""Flat schedules of least total buffer memory.

A flat schedule needs, per edge, the largest token count it reaches; the
least total over all schedules is what we look for.  Fixing a capacity per
edge turns the question into liveness of a bounded graph, which a greedy
execution decides exactly (see ``execution.Executor``).  So:

* Heuristic (any size): start every edge at its two-actor optimum
  ``prod + cons - gcd + delay mod gcd`` (the per-edge lower bound) and run
  the iteration greedily within those capacities.  Whenever everything is
  blocked, the blocked actors wait on each other round a cycle (of data
  edges lacking tokens and full edges lacking room); that cycle on its own
  cannot complete.  Enlarge the one capacity on it that lets the cycle
  complete with the least growth, and go on from where the run stopped
  (larger capacities keep every firing so far legal, and by monotonicity
  continuing is as good as restarting).  The cost is one iteration's worth
  of batches plus a small search per blocked cycle.
* Exact (small graphs): best-first search over capacity vectors in order of
  their total, from the per-edge bounds upwards in steps of each edge's gcd
  (the only sizes a buffer can reach).  A vector that deadlocks shows a cycle
  of waits; every sufficient vector above it must enlarge one of that
  cycle's capacities, so those are the only successors.  The first live
  vector is optimal.  The search is bounded by an evaluation budget; when it
  runs out, the heuristic's schedule stands and is reported not proven.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import Sequence

from ._indexed import IndexedGraph
from .buffers import min_edge_bound
from .execution import Executor, deadlock_error, least_extra_tokens
from .graph import SdfEdge

# Per blocked cycle, the number of its capacities we size a growth for.
_GROWTH_EDGES_TRIED = 8
_HEURISTIC = "capacity-growing heuristic"


@dataclass
class FlatSchedule:
    """A flat schedule as ``[actor index, count]`` runs, with edge peaks."""

    runs: list[list[int]]
    sizes: list[int]
    optimal: bool
    method: str


def _lower_capacities(ig: IndexedGraph) -> list[int]:
    return [
        ig.delay[e] if ig.is_self_loop(e) else min_edge_bound(ig.prod[e], ig.cons[e], ig.delay[e])
        for e in range(ig.edge_count)
    ]


def _total(ig: IndexedGraph, sizes: Sequence[int]) -> int:
    return sum(size for e, size in enumerate(sizes) if not ig.is_self_loop(e))


def heuristic_schedule(ig: IndexedGraph, repetitions: Sequence[int]) -> FlatSchedule:
    """Capacity-growing greedy execution; see the module docstring."""
    capacities = _lower_capacities(ig)
    executor = Executor(ig, repetitions, capacities=capacities, record=True)
    while not executor.run():
        cycle = executor.blocked_cycle()
        space_edges = [e for e, is_space in cycle if is_space]
        if not space_edges:
            # Only possible if the graph itself deadlocks.
            raise deadlock_error(ig, [e for e, _ in cycle])
        mini = _wait_cycle_graph(ig, cycle, capacities)
        best = None
        for e in space_edges[:_GROWTH_EDGES_TRIED]:
            position = cycle.index((e, True))
            growth = least_extra_tokens(mini, position, math.gcd(ig.prod[e], ig.cons[e]))
            if best is None or growth < best[0]:
                best = (growth, e)
        growth, e = best
        capacities[e] += growth
        executor.wake(ig.src[e])
    sizes = list(executor.peak)
    if _total(ig, sizes) == _total(ig, _lower_capacities(ig)):
        return FlatSchedule(executor.runs, sizes, True, f"{_HEURISTIC}, at the per-edge lower bound")
    return FlatSchedule(executor.runs, sizes, False, f"{_HEURISTIC}, not proven optimal")


def _wait_cycle_graph(
    ig: IndexedGraph, cycle: list[tuple[int, bool]], capacities: Sequence[int]
) -> IndexedGraph:
    """A cycle of waits as a stand-alone SDF graph.

    A data wait is the edge itself; a space wait on edge ``e`` is the reverse
    edge of the bounded-buffer model: the consumer hands ``cons`` free places
    per firing to the producer, which takes ``prod``; ``capacity - delay``
    places are free initially.
    """
    edges = []
    for e, is_space in cycle:
        src, dst = ig.names[ig.src[e]], ig.names[ig.dst[e]]
        if is_space:
            edges.append(SdfEdge(dst, src, ig.cons[e], ig.prod[e], capacities[e] - ig.delay[e]))
        else:
            edges.append(ig.edges[e])
    return IndexedGraph([edge.src for edge in edges], edges)


def exact_schedule(
    ig: IndexedGraph,
    repetitions: Sequence[int],
    incumbent: FlatSchedule,
    max_evaluations: int,
) -> FlatSchedule:
    """Best-first capacity search below ``incumbent``; see the module docstring.

    Returns a schedule proven optimal, or ``incumbent`` (marked optimal when
    the search showed nothing cheaper exists, unproven when the budget of
    ``max_evaluations`` runs ran out).
    """
    if incumbent.optimal:
        return incumbent
    start = tuple(_lower_capacities(ig))
    steps = [
        0 if ig.is_self_loop(e) else math.gcd(ig.prod[e], ig.cons[e]) for e in range(ig.edge_count)
    ]
    ceiling = _total(ig, incumbent.sizes)
    frontier = [(_total(ig, start), start)]
    seen = {start}
    evaluations = 0
    while frontier:
        total, capacities = heapq.heappop(frontier)
        if total >= ceiling:
            break
        if evaluations == max_evaluations:
            return FlatSchedule(
                incumbent.runs, incumbent.sizes, False,
                f"{_HEURISTIC}, not proven optimal (exact search stopped after {evaluations} runs)",
            )
        evaluations += 1
        executor = Executor(ig, repetitions, capacities=list(capacities), record=True)
        if executor.run():
            return FlatSchedule(executor.runs, list(executor.peak), True, "exact capacity search, optimal")
        for e, is_space in executor.blocked_cycle():
            if is_space:
                grown = list(capacities)
                grown[e] += steps[e]
                grown = tuple(grown)
                if grown not in seen:
                    seen.add(grown)
                    heapq.heappush(frontier, (total + steps[e], grown))
    return FlatSchedule(
        incumbent.runs, incumbent.sizes, True, f"{_HEURISTIC}, proven optimal by exact search"
    )


def min_buffer_schedule(
    ig: IndexedGraph,
    repetitions: Sequence[int],
    exact_max_firings: int,
    exact_max_evaluations: int,
) -> FlatSchedule:
    """Heuristic schedule, then the exact search if the iteration is small.

    The exact search runs only when one iteration has at most
    ``exact_max_firings`` firings; it tries at most ``exact_max_evaluations``
    capacity vectors.
    """
    schedule = heuristic_schedule(ig, repetitions)
    if sum(repetitions) <= exact_max_firings:
        schedule = exact_schedule(ig, repetitions, schedule, exact_max_evaluations)
    return schedule
