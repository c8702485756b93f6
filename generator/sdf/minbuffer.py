"""Flat schedules of least total buffer memory.

A flat schedule needs, per edge, the largest token count it reaches; the
least total over all schedules is what we look for.  Fixing a capacity per
edge turns the question into liveness of a bounded graph, which a greedy
execution decides exactly (see ``execution.Executor``).  So:

* Heuristic (any size): start every edge at its two-actor optimum
  ``prod + cons - gcd + delay mod gcd`` (the per-edge lower bound) and run
  the iteration greedily within those capacities.  Whenever everything is
  blocked, pick the actor that has its input data and needs the least extra
  output room, enlarge just those outputs by what one firing needs, and go
  on.  Never restarts, so it costs one iteration's worth of batches.
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
from .execution import Executor, deadlock_error


@dataclass
class FlatSchedule:
    """A flat schedule as ``[actor index, count]`` runs, with edge peaks."""

    runs: list[list[int]]
    sizes: list[int]
    optimal: bool


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
    tokens = executor.tokens
    while not executor.run():
        best = None
        for a in sorted(executor.space_blocked):
            if not executor.data_limit(a):
                executor.space_blocked.discard(a)
                continue
            growth = sum(
                max(0, tokens[e] + ig.prod[e] - capacities[e]) for e in ig.out_edges[a]
            )
            if best is None or growth < best[0]:
                best = (growth, a)
        if best is None:
            # Only possible if the graph itself deadlocks.
            raise deadlock_error(ig, [e for e, _ in executor.blocked_cycle()])
        a = best[1]
        for e in ig.out_edges[a]:
            capacities[e] = max(capacities[e], tokens[e] + ig.prod[e])
        executor.space_blocked.discard(a)
        executor.wake(a)
    sizes = executor.peak
    optimal = _total(ig, sizes) == _total(ig, _lower_capacities(ig))
    return FlatSchedule(executor.runs, list(sizes), optimal)


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
    steps = [0 if ig.is_self_loop(e) else math.gcd(ig.prod[e], ig.cons[e]) for e in range(ig.edge_count)]
    ceiling = _total(ig, incumbent.sizes)
    frontier = [(_total(ig, start), start)]
    seen = {start}
    evaluations = 0
    while frontier:
        total, capacities = heapq.heappop(frontier)
        if total >= ceiling:
            break
        if evaluations == max_evaluations:
            return incumbent
        evaluations += 1
        executor = Executor(ig, repetitions, capacities=list(capacities), record=True)
        if executor.run():
            return FlatSchedule(executor.runs, list(executor.peak), True)
        for e, is_space in executor.blocked_cycle():
            if is_space:
                grown = list(capacities)
                grown[e] += steps[e]
                grown = tuple(grown)
                if grown not in seen:
                    seen.add(grown)
                    heapq.heappush(frontier, (total + steps[e], grown))
    return FlatSchedule(incumbent.runs, incumbent.sizes, True)


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
