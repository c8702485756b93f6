"""Symbolic execution of one iteration, and deadlock detection built on it.

The :class:`Executor` fires actors from a worklist, each time as many firings
in a row as the tokens (and, optionally, buffer capacities) allow, so a graph
with large repetition counts costs a few batches per actor rather than one
step per firing.  By the monotonicity of SDF, whether one iteration completes
does not depend on the order of firings, so a greedy executor decides
deadlock exactly (Lee & Messerschmitt 1987).
"""

from __future__ import annotations

from collections import deque
from typing import Sequence

from ._indexed import IndexedGraph
from .errors import DeadlockError, GraphError
from .graph import SdfGraph
from .repetitions import compute_repetitions

# On deadlocked cycles longer than this, only the first edge's missing tokens
# are sized instead of every edge's (each is a binary search).
_MISSING_TOKEN_EDGES_TRIED = 8


class Executor:
    """One iteration of an SDF graph, fired greedily in batches.

    ``capacities`` (one per edge, or None for unbounded) bound the tokens an
    edge may hold: a producer fires only when the results fit.  That is the
    same as adding, for each edge, a reverse "space" edge carrying
    ``capacity - tokens`` tokens, so the executor still decides liveness of
    the bounded graph exactly.  A caller may raise capacities while the
    run is stopped, then :meth:`wake` the producer and :meth:`run` again.
    ``runs`` records the firings as ``[actor, count]`` pairs when ``record``
    is set; ``peak`` is the most tokens each edge has held.
    """

    def __init__(
        self,
        ig: IndexedGraph,
        repetitions: Sequence[int],
        capacities: list[int] | None = None,
        initial_tokens: Sequence[int] | None = None,
        record: bool = False,
    ) -> None:
        self.ig = ig
        self.tokens = list(initial_tokens if initial_tokens is not None else ig.delay)
        self.peak = list(self.tokens)
        self.remaining = list(repetitions)
        self.capacities = capacities
        self.runs: list[list[int]] | None = [] if record else None
        self._queue = deque(range(ig.actor_count))
        self._queued = [True] * ig.actor_count

    @property
    def finished(self) -> bool:
        return not any(self.remaining)

    def data_limit(self, a: int) -> int:
        """How many more firings of ``a`` its input tokens allow right now."""
        ig, tokens = self.ig, self.tokens
        limit = self.remaining[a]
        for e in ig.in_edges[a]:
            if limit == 0:
                return 0
            limit = min(limit, tokens[e] // ig.cons[e])
        for e in ig.self_loops[a]:
            # A consistent self-loop gives back what it takes, so it only
            # needs enough tokens for the first firing.
            if tokens[e] < ig.cons[e]:
                return 0
        return limit

    def space_limit(self, a: int, limit: int) -> int:
        """``limit`` reduced to what the output capacities can hold."""
        capacities, ig, tokens = self.capacities, self.ig, self.tokens
        for e in ig.out_edges[a]:
            if limit == 0:
                break
            limit = min(limit, (capacities[e] - tokens[e]) // ig.prod[e])
        return limit

    def batch_size(self, a: int) -> int:
        """How many firings of ``a`` can happen back to back right now."""
        limit = self.data_limit(a)
        if limit and self.capacities is not None:
            limit = self.space_limit(a, limit)
        return limit

    def fire(self, a: int, count: int) -> None:
        """Fire ``a`` ``count`` times in a row (the caller checked it may)."""
        ig, tokens, queue, queued = self.ig, self.tokens, self._queue, self._queued
        for e in ig.in_edges[a]:
            tokens[e] -= count * ig.cons[e]
            if self.capacities is not None:
                producer = ig.src[e]
                if not queued[producer]:
                    queued[producer] = True
                    queue.append(producer)
        for e in ig.out_edges[a]:
            tokens[e] += count * ig.prod[e]
            if tokens[e] > self.peak[e]:
                self.peak[e] = tokens[e]
            consumer = ig.dst[e]
            if not queued[consumer]:
                queued[consumer] = True
                queue.append(consumer)
        self.remaining[a] -= count
        if self.runs is not None:
            if self.runs and self.runs[-1][0] == a:
                self.runs[-1][1] += count
            else:
                self.runs.append([a, count])
        # No need to requeue ``a``: a maximal batch leaves it waiting for a
        # producer or a consumer, and their firings requeue it.

    def run(self) -> bool:
        """Fire until nothing is enabled; True when the iteration completed."""
        queue, queued = self._queue, self._queued
        while queue:
            a = queue.popleft()
            queued[a] = False
            count = self.batch_size(a)
            if count:
                self.fire(a, count)
        return self.finished

    def wake(self, a: int) -> None:
        """Put ``a`` back on the worklist (after its output capacities grew)."""
        if not self._queued[a]:
            self._queued[a] = True
            self._queue.append(a)

    def blocking_edge(self, a: int) -> tuple[int, bool]:
        """An edge that stops blocked actor ``a``: ``(edge, is_space)``.

        A data edge lacks tokens (its producer is the actor ``a`` waits for);
        a space edge lacks room (``a`` waits for its consumer).
        """
        ig, tokens = self.ig, self.tokens
        for e in ig.in_edges[a]:
            if tokens[e] < ig.cons[e]:
                return e, False
        for e in ig.self_loops[a]:
            if tokens[e] < ig.cons[e]:
                return e, False
        if self.capacities is not None:
            for e in ig.out_edges[a]:
                if tokens[e] + ig.prod[e] > self.capacities[e]:
                    return e, True
        raise AssertionError(f"actor {ig.names[a]} is not blocked")

    def blocked_cycle(self) -> list[tuple[int, bool]]:
        """A cycle of blocked actors, each waiting for the next one back.

        Call only after :meth:`run` returned False.  Returned in the direction
        of the waits' causes: for data edges that is the direction of the
        edges, so a cycle of data edges is a directed cycle of the graph.
        Every actor an unfinished actor waits for is unfinished itself (a
        finished producer has delivered all its tokens, a finished consumer
        has taken them all), so following waits must close a cycle.
        """
        ig = self.ig
        start = next(a for a, left in enumerate(self.remaining) if left)
        seen: dict[int, int] = {}
        waits: list[tuple[int, bool]] = []
        a = start
        while a not in seen:
            seen[a] = len(waits)
            e, is_space = self.blocking_edge(a)
            waits.append((e, is_space))
            a = ig.dst[e] if is_space else ig.src[e]
        cycle = waits[seen[a]:]
        cycle.reverse()
        return cycle


def execute_iteration(ig: IndexedGraph, repetitions: Sequence[int]) -> list[list[int]]:
    """Run one iteration as soon as possible; the ``[actor, count]`` runs.

    Raises DeadlockError when the graph cannot complete the iteration.
    """
    executor = Executor(ig, repetitions, record=True)
    if not executor.run():
        raise deadlock_error(ig, [e for e, _ in executor.blocked_cycle()])
    return executor.runs


def check_deadlock(graph: SdfGraph, repetitions: dict[str, int] | None = None) -> None:
    """Raise DeadlockError unless ``graph`` completes an iteration.

    ``repetitions`` defaults to the graph's repetition vector (which raises
    InconsistentGraphError on an inconsistent graph).
    """
    ig = IndexedGraph.from_graph(graph)
    if repetitions is None:
        counts = compute_repetitions(ig)
    else:
        missing = [name for name in ig.names if name not in repetitions]
        if missing:
            raise GraphError(f"repetition counts missing for {', '.join(missing)}")
        counts = [repetitions[name] for name in ig.names]
    execute_iteration(ig, counts)


def least_extra_tokens(ig: IndexedGraph, edge: int, step: int = 1) -> int:
    """Fewest extra initial tokens on ``edge`` for ``ig`` to complete an iteration.

    The answer is a positive multiple of ``step``.  ``ig`` is meant to be
    small, typically one cycle.  Liveness only grows with tokens, so this is
    a binary search; tokens for a whole iteration's consumption on ``edge``
    always suffice when ``ig`` is a cycle (the rest is then a chain).
    """
    repetitions = compute_repetitions(ig)
    needed = max(1, repetitions[ig.dst[edge]] * ig.cons[edge] - ig.delay[edge])
    low, high = 1, -(-needed // step)

    def completes(steps: int) -> bool:
        tokens = list(ig.delay)
        tokens[edge] += steps * step
        return Executor(ig, repetitions, initial_tokens=tokens).run()

    while low < high:
        middle = (low + high) // 2
        if completes(middle):
            high = middle
        else:
            low = middle + 1
    return low * step


def missing_tokens(ig: IndexedGraph, cycle: list[int], edge: int) -> int:
    """Fewest extra initial tokens on ``edge`` that let directed ``cycle`` complete."""
    sub = ig.subgraph([ig.src[e] for e in cycle], cycle)
    return least_extra_tokens(sub, cycle.index(edge))


def deadlock_error(ig: IndexedGraph, cycle: list[int]) -> DeadlockError:
    """The DeadlockError for a directed ``cycle`` of edges lacking tokens.

    Sizes the missing tokens for each edge of the cycle (only the first for
    long cycles) and names the edge that needs the fewest.
    """
    tried = cycle if len(cycle) <= _MISSING_TOKEN_EDGES_TRIED else cycle[:1]
    best_edge, best_count = tried[0], None
    for e in tried:
        count = missing_tokens(ig, cycle, e)
        if best_count is None or count < best_count:
            best_edge, best_count = e, count
    actors = ", ".join(dict.fromkeys(ig.names[ig.src[e]] for e in cycle))
    lines = "\n".join(f"  {ig.edges[e].describe()}" for e in cycle)
    edge = ig.edges[best_edge]
    message = (
        f"deadlock: actors {actors} wait for each other round this cycle, "
        f"which carries too few initial tokens:\n{lines}\n"
        f"edge {edge.label} needs {best_count} more initial "
        f"token{'s' if best_count != 1 else ''} (it has {edge.delay}) "
        "for the cycle to complete an iteration"
    )
    return DeadlockError(message, [ig.edges[e] for e in cycle], edge, best_count)
