"""SDF analysis of a checked model's dataflows, and ``easylab analyze``.

Each dataflow becomes an :class:`~easylab.sdf.SdfGraph` whose nodes are its
actor instances plus one node per external endpoint: ``in:NAME`` for a var,
param, device datum or channel read by the graph, ``out:NAME`` for one it
writes. A var, param or device endpoint fires exactly once per activation
(it has a fixed rate: the device port's, or 1); a channel endpoint moves
one token per firing, so its repetition count is the number of tokens the
graph moves per activation. One activation is one iteration of the graph.

Buffer figures (totals, bounds) count the edges between actors only: the
external endpoints are task-local copies, not buffers.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core.source import Diagnostics, note
from ..frontend.model import CheckedModel, DataflowInfo, Endpoint
from . import sdf
from .sdf.analysis import SCHEDULE_NAMES

SOURCE_PREFIX, SINK_PREFIX = "in:", "out:"


@dataclass
class DataflowAnalysis:
    """The SDF analysis of one dataflow, external endpoints included."""

    dataflow: DataflowInfo
    graph: sdf.SdfGraph
    result: sdf.Analysis
    node_of_edge: dict[int, tuple[str, str]]  # id(EdgeInfo) -> (src node, dst node)
    external_nodes: dict[str, Endpoint]

    @property
    def actor_repetitions(self) -> dict[str, int]:
        return {a: n for a, n in self.result.repetitions.items() if a not in self.external_nodes}

    def internal_buffers(self) -> list[tuple[sdf.SdfEdge, int]]:
        return [(e, size) for e, size in self.result.buffers
                if e.src not in self.external_nodes and e.dst not in self.external_nodes]

    def internal_graph(self) -> sdf.SdfGraph:
        actors = [a for a in self.graph.actors if a not in self.external_nodes]
        edges = [e for e in self.graph.edges if e.src not in self.external_nodes and e.dst not in self.external_nodes]
        return sdf.SdfGraph(actors, edges, name=self.dataflow.name)

    def actor_schedule(self) -> sdf.Schedule:
        """The schedule without the external endpoints (what a reader wants to see)."""
        return _strip(self.result.schedule, set(self.external_nodes))

    def summary(self) -> dict:
        """The JSON object of ``easylab analyze --json`` for this dataflow."""
        internal = self.internal_graph()
        buffers = self.internal_buffers()
        return {
            "name": self.dataflow.name,
            "repetitions": self.actor_repetitions,
            "schedule": self.actor_schedule().text(),
            "buffers": [{"src": e.src, "dst": e.dst, "size": size} for e, size in buffers],
            "buffer_total": sum(size for _, size in buffers),
            "sas_lower_bound": sdf.sas_lower_bound(internal),
            "edge_lower_bound": sdf.edge_lower_bound(internal),
            "schedule_kind": self.result.kind,
            "external_rates": {name: self.result.repetitions[name] * _node_rate(ep)
                               for name, ep in self.external_nodes.items()},
        }

    def render_text(self) -> str:
        s = self.summary()
        lines = [f"dataflow {s['name']} ({SCHEDULE_NAMES[s['schedule_kind']]} schedule)"]
        lines.append("  repetitions: " + (", ".join(f"{a}={n}" for a, n in s["repetitions"].items()) or "-"))
        lines.append(f"  schedule:    {s['schedule'] or '(no actors)'}")
        rows = [("edge", "rates", "delay", "buffer")]
        for e, size in self.internal_buffers():
            rows.append((e.label, f"{e.prod}:{e.cons}", str(e.delay), str(size)))
        if len(rows) > 1:
            widths = [max(len(r[i]) for r in rows) for i in range(4)]
            for i, r in enumerate(rows):
                lines.append("    " + r[0].ljust(widths[0]) + "  " +
                             "  ".join(c.rjust(w) for c, w in zip(r[1:], widths[1:])))
                if i == 0:
                    lines.append("    " + "-" * (sum(widths) + 6))
        lines.append(f"  buffer total: {s['buffer_total']} tokens (single-appearance lower bound "
                     f"{s['sas_lower_bound']}, per-edge lower bound {s['edge_lower_bound']})")
        if s["external_rates"]:
            lines.append("  per activation: " + ", ".join(f"{n} {r}" for n, r in s["external_rates"].items()))
        return "\n".join(lines) + "\n"


def _node_rate(ep: Endpoint) -> int:
    return ep.rate if ep.rate is not None else 1


def _strip(schedule: sdf.Schedule, drop: set[str]) -> sdf.Schedule:
    def walk(nodes):
        out = []
        for n in nodes:
            if isinstance(n, sdf.Fire):
                if n.actor not in drop:
                    out.append(n)
            else:
                body = walk(n.body)
                if body:
                    out.extend(sdf.repeat(n.count, body))
        return out
    return sdf.Schedule(tuple(walk(schedule.body)))


def build_graph(df: DataflowInfo) -> tuple[sdf.SdfGraph, dict, dict]:
    """The SDF graph of a dataflow, with one node per external endpoint."""
    actors = list(df.instances)
    externals: dict[str, Endpoint] = {}
    node_of_edge: dict[int, tuple[str, str]] = {}
    edges = []
    for e in df.edges:
        ends = []
        for end, prefix in ((e.src, SOURCE_PREFIX), (e.dst, SINK_PREFIX)):
            if end.kind == "actor":
                ends.append(end.target.name)
            else:
                node = prefix + end.label
                if node not in externals:
                    externals[node] = end
                    actors.append(node)
                ends.append(node)
        prod = e.src.rate if e.src.rate is not None else 1
        cons = e.dst.rate if e.dst.rate is not None else 1
        edges.append(sdf.SdfEdge(ends[0], ends[1], prod, cons, len(e.initial_tokens), name=e.label, loc=e.decl.span))
        node_of_edge[id(e)] = (ends[0], ends[1])
    return sdf.SdfGraph(actors, edges, name=df.name), node_of_edge, externals


def analyze_dataflow(df: DataflowInfo, diags: Diagnostics, schedule: str | None = None,
                     cache: sdf.AnalysisCache | None = None) -> DataflowAnalysis | None:
    """Analyse one dataflow; errors (with the edges involved) go to ``diags``.

    ``cache``, if given, answers for a graph it has analysed before (see
    :mod:`easylab.analysis.sdf.cache`): same result, same diagnostics."""
    graph, node_of_edge, externals = build_graph(df)
    kind = schedule or df.decl.schedule or "sas"
    try:
        result = cache.analyze(graph, kind) if cache is not None else sdf.analyze(graph, kind)
    except (sdf.InconsistentGraphError, sdf.DeadlockError) as err:
        _report(err, df, diags)
        return None
    except sdf.ScheduleError as err:  # the schedule kind asked for does not exist or is too long
        diags.error(df.decl.name_span, f"dataflow '{df.name}': {err.message}")
        return None
    ok = True
    for node, ep in externals.items():
        count = result.repetitions[node]
        if ep.kind == "channel" or count == 1:
            continue
        ok = False
        edge = next(e for e in df.edges if node in node_of_edge[id(e)])
        rate = _node_rate(ep)
        what = {"var": "a var", "param": "a param", "device": "a device port"}[ep.kind]
        if node.startswith(SOURCE_PREFIX):
            diags.error(edge.decl.span,
                        f"'{ep.label}' gives {rate} token{'s' if rate != 1 else ''} per activation ({what}), "
                        f"but dataflow '{df.name}' consumes {count * rate} per iteration through this edge",
                        "change the rates so that one iteration reads the port once"
                        + (f", or declare the device port with 'rate {count * rate}'" if ep.kind == "device" else ""))
        else:
            diags.error(edge.decl.span,
                        f"'{ep.label}' takes {rate} token{'s' if rate != 1 else ''} per activation ({what}), "
                        f"but dataflow '{df.name}' produces {count * rate} per iteration into it",
                        "change the rates so that one iteration writes the port once"
                        + (f", or declare the device port with 'rate {count * rate}'" if ep.kind == "device" else ""))
    if not ok:
        return None
    return DataflowAnalysis(df, graph, result, node_of_edge, externals)


def _report(err: sdf.SdfError, df: DataflowInfo, diags: Diagnostics) -> None:
    located = [e for e in err.edges if e.loc is not None]
    if not located:
        diags.error(df.decl.name_span, f"dataflow '{df.name}': {err.message}")
        return
    first = getattr(err, "missing_edge", None) or located[0]
    notes = tuple(note(e.loc, f"on the cycle: {e.describe()}") for e in located if e is not first)
    if isinstance(err, sdf.DeadlockError):
        message = (f"dataflow '{df.name}' deadlocks: the cycle through '{first.label}' lacks initial tokens; "
                   f"it needs {err.missing} more here")
        hint = f"add initial tokens: {first.label} delay {first.delay + err.missing}"
    else:
        message = f"dataflow '{df.name}' has inconsistent rates: {err.message}"
        hint = "the products of production over consumption rates around a cycle must be 1"
    diags.error(first.loc, message, hint, notes)


def analyze_model(model: CheckedModel, diags: Diagnostics, schedule: str | None = None,
                  cache: sdf.AnalysisCache | None = None) -> None:
    """Analyse every dataflow, storing the result in ``DataflowInfo.analysis``
    (``cache``: see :func:`analyze_dataflow`)."""
    for df in model.dataflows.values():
        df.analysis = analyze_dataflow(df, diags, schedule, cache)
