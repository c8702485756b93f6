"""Single-appearance schedules (SAS): flat, and looped with least buffers.

A single-appearance schedule names every actor once, which keeps generated
code small; the loops around the names decide the buffer sizes.

Acyclic graphs: APGAN and RPMC (``clustering``) each propose a lexical order,
DPPO (``dppo``) nests loops optimally for it, and the cheapest wins.  The
topological order of the flat SAS is always a third candidate, so the result
never needs more memory than the flat SAS.

Cyclic graphs are handled level by level as in Bhattacharyya, Murthy & Lee's
loose interdependence algorithm.  A *level* is a set of actors with counts
for one iteration of that set (a weakly connected component with the
repetition vector, at the top).  Edges whose delay covers a whole iteration's
traffic at that level (``delay >= count[dst] * cons``) can never starve their
consumer there, so they impose no order.  The rest are split into strongly
connected components; the components form an acyclic graph scheduled as
above, each non-trivial component becoming one node that fires ``gcd`` of its
members' counts times and runs its own level inside.  A component that stays
strongly connected after dropping such edges is *tightly interdependent*:
no single-appearance schedule exists for it, and it gets the flat
minimum-buffer schedule of ``minbuffer`` (actors may then appear more than
once, only inside that component's loop).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

from ._digraph import strongly_connected_components, topological_order
from ._indexed import IndexedGraph
from .clustering import LevelDag, apgan, bisection
from .dppo import Splits, forward_edges, nested_items, nesting_cost, optimize_nesting, order_lower_bound
from .minbuffer import heuristic_schedule
from .options import SdfOptions
from .repetitions import weakly_connected_components
from .schedule import Fire, Node, Schedule


@dataclass
class SasResult:
    """A looped schedule, how it was found, and whether it is truly SAS."""

    schedule: Schedule
    method: str
    single_appearance: bool
    tight_components: list[list[str]] = field(default_factory=list)


@dataclass
class _Level:
    members: list[int]
    counts: dict[int, int]
    # Acyclic levels: node (position in order) -> child level or actor.
    order: list[int] = field(default_factory=list)
    node_counts: list[int] = field(default_factory=list)
    splits: Splits = field(default_factory=dict)
    node_actor: list[int | None] = field(default_factory=list)
    node_child: list[int | None] = field(default_factory=list)
    method: str | None = None
    # Tightly interdependent levels: a flat schedule instead.
    flat_runs: list[tuple[int, int]] | None = None


def flat_sas(ig: IndexedGraph, repetitions: Sequence[int]) -> Schedule | None:
    """Every actor fired its full count once, in a topological order.

    Edges whose delay covers one iteration's traffic impose no order.
    Returns None when the remaining edges still form a cycle: then no flat
    single-appearance schedule exists.
    """
    succ: list[list[int]] = [[] for _ in range(ig.actor_count)]
    for e in range(ig.edge_count):
        s, d = ig.src[e], ig.dst[e]
        if s != d and ig.delay[e] < repetitions[d] * ig.cons[e]:
            succ[s].append(d)
    order = topological_order(range(ig.actor_count), succ)
    if order is None:
        return None
    return Schedule(tuple(Fire(ig.names[a], repetitions[a]) for a in order))


def best_sas(ig: IndexedGraph, repetitions: Sequence[int], options: SdfOptions) -> SasResult:
    """The looped schedule of least buffer memory our heuristics find."""
    levels: list[_Level] = []
    tops = []
    for members in weakly_connected_components(ig):
        tops.append(len(levels))
        levels.append(_Level(members, {a: repetitions[a] for a in members}))
    # Plan top-down; children are appended, so they follow their parents.
    index = 0
    while index < len(levels):
        _plan_level(ig, levels, index, options)
        index += 1
    # Build bottom-up: children first.
    items: list[list[Node] | None] = [None] * len(levels)
    for index in range(len(levels) - 1, -1, -1):
        items[index] = _level_items(ig, levels[index], items)
    body: list[Node] = []
    for index in tops:
        body.extend(items[index])

    tight = [[ig.names[a] for a in level.members] for level in levels if level.flat_runs is not None]
    methods = sorted({level.method for level in levels if level.method})
    method = " / ".join(methods) if methods else "trivial"
    if tight:
        method += f"; flat minimum-buffer schedules for {len(tight)} tightly interdependent component(s)"
    return SasResult(Schedule(tuple(body)), method, not tight, tight)


def _plan_level(ig: IndexedGraph, levels: list[_Level], index: int, options: SdfOptions) -> None:
    level = levels[index]
    members, counts = level.members, level.counts
    inside = set(members)
    internal = [e for a in members for e in ig.out_edges[a] if ig.dst[e] in inside]

    def traffic(e: int) -> int:
        return counts[ig.dst[e]] * ig.cons[e]

    precedence_succ: dict[int, list[int]] = {a: [] for a in members}
    for e in internal:
        if ig.delay[e] < traffic(e):
            precedence_succ[ig.src[e]].append(ig.dst[e])
    components = strongly_connected_components(members, precedence_succ)
    if len(components) == 1 and len(members) > 1:
        sub = ig.subgraph(members, internal + [e for a in members for e in ig.self_loops[a]])
        flat = heuristic_schedule(sub, [counts[a] for a in members])
        level.flat_runs = [(members[a], count) for a, count in flat.runs]
        return

    node_of: dict[int, int] = {}
    node_counts = []
    for node, component in enumerate(components):
        for a in component:
            node_of[a] = node
        g = math.gcd(*(counts[a] for a in component))
        node_counts.append(g)
        if len(component) == 1:
            level.node_actor.append(component[0])
            level.node_child.append(None)
        else:
            level.node_actor.append(None)
            level.node_child.append(len(levels))
            levels.append(_Level(component, {a: counts[a] // g for a in component}))
    dag = LevelDag(
        node_counts,
        [component[0] for component in components],
        [
            (node_of[ig.src[e]], node_of[ig.dst[e]], traffic(e), ig.delay[e] < traffic(e))
            for e in internal
            if node_of[ig.src[e]] != node_of[ig.dst[e]]
        ],
    )
    level.order, level.splits, level.method = _plan_dag(dag, options)
    level.node_counts = node_counts


def _plan_dag(dag: LevelDag, options: SdfOptions) -> tuple[list[int], Splits, str | None]:
    """Cheapest of the APGAN, RPMC and topological candidates, after DPPO."""
    if dag.size == 1:
        return [0], {}, None
    traffic = dag.traffic_edges()
    topological = dag.topological_order()
    # (name, its order when known before its nesting, the order and nesting)
    candidates = [
        ("apgan", None, lambda: apgan(dag, options.apgan_search_limit)),
        ("rpmc", None, lambda: bisection(dag, topological, reorder=True)),
        # The flat SAS's own order: keeps the result at or below the flat SAS.
        ("topological", topological, lambda: bisection(dag, topological, reorder=False)),
    ]
    window = dag.size if dag.size <= options.dppo_max_nodes else options.dppo_window
    solved: dict = {}  # DPPO's nestings by window, shared by the candidates
    best = None
    for name, order, build in candidates:
        hierarchy = None
        if order is None:
            order, hierarchy = build()
        counts = [dag.counts[node] for node in order]
        edges = forward_edges(order, traffic)
        if best is not None and order_lower_bound(counts, edges) >= best[0]:
            continue  # no nesting of this order beats the best so far: spare building it and DPPO
        if hierarchy is None:
            hierarchy = build()[1]
        splits = optimize_nesting(counts, edges, hierarchy, window, solved)
        cost = nesting_cost(counts, edges, splits)
        if best is None or cost < best[0]:
            best = (cost, order, splits, f"{name}+dppo")
    _, order, splits, method = best
    return order, splits, method


def _level_items(ig: IndexedGraph, level: _Level, items: list) -> list[Node]:
    if level.flat_runs is not None:
        return [Fire(ig.names[a], count) for a, count in level.flat_runs]

    def leaf_items(position: int) -> list[Node]:
        node = level.order[position]
        child = level.node_child[node]
        if child is not None:
            return list(items[child])
        return [Fire(ig.names[level.node_actor[node]], 1)]

    counts = [level.node_counts[node] for node in level.order]
    return nested_items(counts, level.splits, leaf_items)
