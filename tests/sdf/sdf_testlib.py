"""Shared helpers of the SDF tests: random graph strategies and a reference
simulator written independently of the library (firing by firing)."""

from __future__ import annotations

import math
from fractions import Fraction

from hypothesis import strategies as st

from easylab.analysis.sdf import SdfGraph

# Repetition counts drawn from the divisors of 12 keep every reduced ratio
# q[u] : q[v] within 12, so rates up to 12 can always balance an edge.
COUNTS = (1, 2, 3, 4, 6, 12)
MAX_RATE = 12


def balanced_rates(draw, q_src: int, q_dst: int) -> tuple[int, int]:
    """Rates (prod, cons) with q_src * prod == q_dst * cons, both <= 12."""
    g = math.gcd(q_src, q_dst)
    prod, cons = q_dst // g, q_src // g
    k = draw(st.integers(1, MAX_RATE // max(prod, cons)))
    return prod * k, cons * k


@st.composite
def consistent_graphs(draw, max_actors: int = 30, cyclic: bool = False, delays: str = "enough"):
    """A consistent graph, acyclic unless ``cyclic``.

    Forward edges go from a lower to a higher actor number.  With ``cyclic``,
    back edges are added; ``delays="enough"`` gives each a whole iteration's
    traffic or more (always live), ``"random"`` gives it a small random delay
    (the graph may deadlock).
    """
    n = draw(st.integers(1, max_actors))
    q = [draw(st.sampled_from(COUNTS)) for _ in range(n)]
    graph = SdfGraph([f"a{i}" for i in range(n)])
    for i in range(1, n):
        # Mostly connected; now and then a new component starts.
        if draw(st.integers(0, 9)) == 0:
            continue
        nearby = draw(st.booleans())   # chains and bushy trees
        parent = draw(st.integers(max(0, i - 4) if nearby else 0, i - 1))
        prod, cons = balanced_rates(draw, q[parent], q[i])
        graph.add_edge(f"a{parent}", f"a{i}", prod, cons, draw(st.sampled_from((0, 0, 0, 1, 3))))
    extra = draw(st.integers(0, n // 2 + 1)) if n > 1 else 0
    for _ in range(extra):
        u, v = sorted(draw(st.lists(st.integers(0, n - 1), min_size=2, max_size=2, unique=True)))
        prod, cons = balanced_rates(draw, q[u], q[v])
        graph.add_edge(f"a{u}", f"a{v}", prod, cons, draw(st.sampled_from((0, 0, 2))))
    if cyclic and n > 1:
        for _ in range(draw(st.integers(1, n // 3 + 1))):
            u, v = sorted(draw(st.lists(st.integers(0, n - 1), min_size=2, max_size=2, unique=True)))
            prod, cons = balanced_rates(draw, q[v], q[u])   # edge v -> u, backwards
            if delays == "enough":
                # q[u] * cons is one iteration's traffic when q has gcd 1;
                # more when it has not, so this always suffices.
                delay = q[u] * cons + draw(st.integers(0, 3))
            else:
                delay = draw(st.integers(0, 2 * max(prod, cons)))
            graph.add_edge(f"a{v}", f"a{u}", prod, cons, delay)
    if draw(st.integers(0, 4)) == 0:
        a = draw(st.integers(0, n - 1))
        rate = draw(st.integers(1, 3))
        graph.add_edge(f"a{a}", f"a{a}", rate, rate, rate + draw(st.integers(0, 2)))
    return graph


def simulate(graph: SdfGraph, firings, repetitions: dict[str, int]) -> dict:
    """Fire one by one; return the peak token count per edge.

    Asserts admissibility (no edge below zero, self-loops consume before they
    produce), one iteration exactly, and periodicity.
    """
    tokens = {edge: edge.delay for edge in graph.edges}
    peak = dict(tokens)
    inputs = {actor: [] for actor in graph.actors}
    outputs = {actor: [] for actor in graph.actors}
    for edge in graph.edges:
        inputs[edge.dst].append(edge)
        outputs[edge.src].append(edge)
    fired = {actor: 0 for actor in graph.actors}
    for actor in firings:
        fired[actor] += 1
        for edge in inputs[actor]:
            tokens[edge] -= edge.cons
            assert tokens[edge] >= 0, f"{edge.describe()} goes negative firing {actor}"
        for edge in outputs[actor]:
            tokens[edge] += edge.prod
            peak[edge] = max(peak[edge], tokens[edge])
    assert fired == repetitions, "not exactly one iteration"
    assert all(tokens[edge] == edge.delay for edge in graph.edges), "not periodic"
    return peak


def cycle_completes(cycle, extra_edge=None, extra: int = 0) -> bool:
    """Whether a directed cycle of edges, alone, completes one iteration."""
    actors = [edge.src for edge in cycle]
    # Local repetition vector of the cycle by propagating rates.
    rate = {actors[0]: Fraction(1)}
    for edge in cycle[:-1]:
        rate[edge.dst] = rate[edge.src] * edge.prod / edge.cons
    scale = math.lcm(*(r.denominator for r in rate.values()))
    counts = {a: int(r * scale) for a, r in rate.items()}
    g = math.gcd(*counts.values())
    remaining = {a: c // g for a, c in counts.items()}
    tokens = {id(edge): edge.delay + (extra if edge is extra_edge else 0) for edge in cycle}
    into = {edge.dst: edge for edge in cycle}
    out = {edge.src: edge for edge in cycle}
    progress = True
    while progress:
        progress = False
        for a in actors:
            edge_in = into[a]
            if remaining[a] and tokens[id(edge_in)] >= edge_in.cons:
                tokens[id(edge_in)] -= edge_in.cons
                tokens[id(out[a])] += out[a].prod
                remaining[a] -= 1
                progress = True
    return not any(remaining.values())


def cd2dat(with_g: bool = False) -> SdfGraph:
    """The CD-to-DAT sample-rate converter, optionally with a 7th actor G."""
    edges = [("A", "B", 1, 1), ("B", "C", 2, 3), ("C", "D", 2, 7), ("D", "E", 8, 7), ("E", "F", 5, 1)]
    if with_g:
        edges.append(("F", "G", 1, 160))
    return SdfGraph.from_edges(edges, name="cd2dat")
