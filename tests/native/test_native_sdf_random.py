"""Random consistent multi-rate dataflows: generated as .elab text, built
with gcc for the host board with both schedule kinds, run, and every
checksum that reaches a var compared with an independent Python
interpretation of the same SDF semantics (native_testlib.Sdf).

Graphs: one or two sources, then stages (one input) and joins (two
inputs), each reading earlier nodes; a join may read back from itself or a
node downstream of it (a feedback cycle) through an edge with enough initial
tokens for one whole iteration; some forward edges carry delays too, as
zeros (`delay n`) or listed values (`delay [..]`). Rates follow from a
repetition count drawn per node. Every node without consumers (and some
others) feeds a checksum actor that writes a var once per activation.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from native_testlib import M32, Sdf, VarSink, build, run

ACTIVATIONS = 5
CFLAGS = "-O0"  # each case compiles two programs: keep them cheap

ACTORS = """\
actor type Src(p: uint16, k: uint32) {
    out y: uint32 rate p
    state n: uint32
    step {{
        uint16_t i;
        for (i = 0u; i < p; i++) { n = n + k; y[i] = n; }
    }}
}

actor type Stage(p: uint16, c: uint16, m: uint32) {
    in  x: uint32 rate c
    out y: uint32 rate p
    state acc: uint32
    step {{
        uint16_t i;
        for (i = 0u; i < c; i++) { acc = acc * m + x[i]; }
        for (i = 0u; i < p; i++) { y[i] = acc + (uint32_t)i * 7u; }
    }}
}

actor type Join(p: uint16, ca: uint16, cb: uint16) {
    in  a: uint32 rate ca
    in  b: uint32 rate cb
    out y: uint32 rate p
    state acc: uint32
    step {{
        uint16_t i;
        for (i = 0u; i < ca; i++) { acc = acc * 31u + a[i]; }
        for (i = 0u; i < cb; i++) { acc = (acc ^ b[i]) * 17u; }
        for (i = 0u; i < p; i++) { y[i] = acc + (uint32_t)i; }
    }}
}

actor type Sum(n: uint16) {
    in  x: uint32 rate n
    out y: uint32
    state s: uint32
    step {{
        uint16_t i;
        for (i = 0u; i < n; i++) { s = s * 31u + x[i]; }
        y = s;
    }}
}
"""


# ---------------------------------------------------------------------- the Python side of the actors


def src_fire(p: int, k: int):
    n = [0]

    def fire(_):
        out = []
        for _ in range(p):
            n[0] = (n[0] + k) & M32
            out.append(n[0])
        return {"y": out}
    return fire


def stage_fire(p: int, m: int):
    acc = [0]

    def fire(t):
        for x in t["x"]:
            acc[0] = (acc[0] * m + x) & M32
        return {"y": [(acc[0] + 7 * i) & M32 for i in range(p)]}
    return fire


def join_fire(p: int):
    acc = [0]

    def fire(t):
        for x in t["a"]:
            acc[0] = (acc[0] * 31 + x) & M32
        for x in t["b"]:
            acc[0] = ((acc[0] ^ x) * 17) & M32
        return {"y": [(acc[0] + i) & M32 for i in range(p)]}
    return fire


def sum_fire():
    s = [0]

    def fire(t):
        for x in t["x"]:
            s[0] = (s[0] * 31 + x) & M32
        return {"y": [s[0]]}
    return fire


# ---------------------------------------------------------------------- random graphs


@dataclass
class Node:
    name: str
    kind: str  # src, stage, join
    q: int
    inputs: list = field(default_factory=list)  # [(port, source node index or None for feedback)]
    p: int = 0
    k: int = 1
    m: int = 1


@dataclass
class Edge:
    src: int
    dst: int
    port: str
    delay: list  # initial tokens
    listed: bool  # `delay [..]` rather than `delay n`


@dataclass
class Graph:
    nodes: list
    edges: list
    sinks: list  # node indices feeding a Sum -> var
    param_k: int  # value of the param used as the first source's k


def descendants(edges, start) -> set:
    seen, todo = {start}, [start]
    while todo:
        n = todo.pop()
        for e in edges:
            if e.src == n and e.dst not in seen:
                seen.add(e.dst)
                todo.append(e.dst)
    return seen


@st.composite
def graphs(draw):
    n_src = draw(st.integers(1, 2))
    n_inner = draw(st.integers(1, 5))
    nodes = [Node(f"s{i}", "src", draw(st.sampled_from([1, 2, 3, 4])),
                  k=draw(st.integers(1, 1000))) for i in range(n_src)]
    edges: list[Edge] = []
    feedback: list[int] = []
    for i in range(n_inner):
        idx = len(nodes)
        kind = draw(st.sampled_from(["stage", "join"]))
        node = Node(f"n{i}", kind, draw(st.sampled_from([1, 2, 3, 4, 6])),
                    m=draw(st.sampled_from([1, 3, 1000003])))
        nodes.append(node)
        edges.append(Edge(draw(st.integers(0, idx - 1)), idx, "x" if kind == "stage" else "a", [], False))
        if kind == "join":
            if draw(st.booleans()):
                feedback.append(idx)  # b filled in once the downstream nodes exist
            else:
                edges.append(Edge(draw(st.integers(0, idx - 1)), idx, "b", [], False))
    for j in feedback:
        down = sorted(descendants(edges, j) - {j}, reverse=True)
        if not down or draw(st.integers(0, 3)) == 3:
            down = [j]  # a self-loop
        edges.append(Edge(draw(st.sampled_from(down)), j, "b", [], False))
    # Output rates: every consumer's repetition count must divide what a
    # producer puts on its edges per iteration.
    for u, node in enumerate(nodes):
        need = 1
        for e in edges:
            if e.src == u:
                qv = nodes[e.dst].q
                need = math.lcm(need, qv // math.gcd(qv, node.q))
        node.p = need * draw(st.integers(1, 2))
    # Delays: enough on feedback edges for one whole iteration of the join.
    for e in edges:
        tokens = nodes[e.src].q * nodes[e.src].p
        is_feedback = e.src >= e.dst
        extra = draw(st.integers(0, 3)) if is_feedback or draw(st.integers(0, 3)) == 0 else 0
        count = (tokens if is_feedback else 0) + extra
        e.listed = 0 < count <= 6 and not draw(st.booleans())
        e.delay = [draw(st.integers(0, 99)) for _ in range(count)] if e.listed else [0] * count
    consumers = {e.src for e in edges if e.src < e.dst}  # forward edges: every component gets a var
    sinks = [u for u in range(len(nodes)) if u not in consumers or draw(st.integers(0, 4)) == 0]
    return Graph(nodes, edges, sinks, draw(st.integers(0, 2 ** 32 - 1)))


def rate_in(g: Graph, e: Edge) -> int:
    """Tokens a firing of e's consumer takes from e."""
    return g.nodes[e.src].q * g.nodes[e.src].p // g.nodes[e.dst].q


def elab(g: Graph) -> str:
    lines = ["model random_sdf", "import std", "", ACTORS,
             f"param k0: uint32 = {g.param_k}"]
    lines += [f"var v{u}: uint32" for u in g.sinks]
    lines += ["", "dataflow G {"]
    for u, n in enumerate(g.nodes):
        ins = {e.port: rate_in(g, e) for e in g.edges if e.dst == u}
        if n.kind == "src":
            k = "k0" if u == 0 else str(n.k)
            lines.append(f"    {n.name} = Src(p = {n.p}, k = {k})")
        elif n.kind == "stage":
            lines.append(f"    {n.name} = Stage(p = {n.p}, c = {ins['x']}, m = {n.m})")
        else:
            lines.append(f"    {n.name} = Join(p = {n.p}, ca = {ins['a']}, cb = {ins['b']})")
    for e in g.edges:
        delay = ""
        if e.listed:
            delay = f" delay [{', '.join(map(str, e.delay))}]"
        elif e.delay:
            delay = f" delay {len(e.delay)}"
        lines.append(f"    {g.nodes[e.src].name}.y -> {g.nodes[e.dst].name}.{e.port}{delay}")
    for u in g.sinks:
        n = g.nodes[u]
        lines.append(f"    sum{u} = Sum(n = {n.q * n.p})")
        lines.append(f"    {n.name}.y -> sum{u}.x")
        lines.append(f"    sum{u}.y -> v{u}")
    lines += ["}", "", "task t period 1 ms { run G }", ""]
    return "\n".join(lines)


def reference(g: Graph, activations: int) -> dict[str, list[int]]:
    sdf = Sdf()
    for u, n in enumerate(g.nodes):
        ins = {e.port: rate_in(g, e) for e in g.edges if e.dst == u}
        if n.kind == "src":
            sdf.add(n.name, src_fire(n.p, g.param_k if u == 0 else n.k), {}, {"y": n.p})
        elif n.kind == "stage":
            sdf.add(n.name, stage_fire(n.p, n.m), ins, {"y": n.p})
        else:
            sdf.add(n.name, join_fire(n.p), ins, {"y": n.p})
    for e in g.edges:
        sdf.connect(g.nodes[e.src].name, "y", g.nodes[e.dst].name, e.port, e.delay)
    vars_ = {}
    for u in g.sinks:
        n = g.nodes[u]
        sdf.add(f"sum{u}", sum_fire(), {"x": n.q * n.p}, {"y": 1})
        sdf.connect(n.name, "y", f"sum{u}", "x")
        vars_[f"v{u}"] = VarSink()
        sdf.add(f"v{u}", vars_[f"v{u}"], {"x": 1}, {})
        sdf.connect(f"sum{u}", "y", f"v{u}", "x")
    q = sdf.repetitions()
    # Every component ends in a var (rate 1 per activation): the drawn counts are the repetition vector.
    assert all(q[n.name] == n.q for n in g.nodes), (q, [n.q for n in g.nodes])
    out = {name: [] for name in vars_}
    for _ in range(activations):
        sdf.iterate(q)
        for name, sink in vars_.items():
            out[name].append(sink.value)
    return out


@settings(max_examples=15, deadline=None, derandomize=True, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow, HealthCheck.data_too_large])
@given(g=graphs())
def test_random_dataflow_matches_the_reference(g, tmp_path_factory):
    d = tmp_path_factory.mktemp("rsdf")
    model = d / "random_sdf.elab"
    model.write_text(elab(g), encoding="utf-8")
    expected = reference(g, ACTIVATIONS)
    with ThreadPoolExecutor(max_workers=2) as pool:
        exes = list(pool.map(lambda kind: build(model, d / kind, cflags=CFLAGS, schedule=kind), ("sas", "min-buffer")))
    texts = []
    for kind, exe in zip(("sas", "min-buffer"), exes):
        r = run(exe, d / f"{kind}.csv", duration=f"{ACTIVATIONS + 1}ms")
        trace = r.trace
        for name, values in expected.items():
            got = [trace.int(name, 1000 * (a + 1)) for a in range(ACTIVATIONS)]
            assert got == values, f"{kind}: {name}\n{model.read_text()}"
        texts.append(r.trace_text)
    assert texts[0] == texts[1]
