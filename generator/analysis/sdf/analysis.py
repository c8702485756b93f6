"""The entry point the CLI calls: analyse a graph and pick a schedule."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

from ...core.collector import cycle_collection_paused
from ._indexed import IndexedGraph
from .buffers import check_schedule, edge_lower_bound, sas_lower_bound
from .errors import ScheduleError
from .execution import execute_iteration
from .graph import SdfEdge, SdfGraph
from .minbuffer import min_buffer_schedule
from .options import SdfOptions
from .repetitions import compute_repetitions
from .sas import best_sas, flat_sas
from .schedule import Schedule

# sas: the looped single-appearance schedule of least buffer memory found;
# flat: the flat single-appearance schedule (each actor's firings in one
# run, in topological order: the simplest loops, the largest buffers);
# min-buffer: a flat schedule of least total buffer memory.
SCHEDULE_KINDS = ("sas", "flat", "min-buffer")
# How reports name them.
SCHEDULE_NAMES = {"sas": "single-appearance", "flat": "flat single-appearance", "min-buffer": "minimum-buffer"}
# The text report shows at most this much of a schedule; JSON has it all.
_REPORT_SCHEDULE_CHARS = 600


@dataclass
class Analysis:
    """Everything known about one graph after :func:`analyze`.

    ``buffers`` lists every edge that is not a self-loop with its buffer size
    under ``schedule``, in graph order; ``buffer_total`` is their sum.
    Self-loops (actor state, in effect) are listed apart in ``self_loops``
    and not counted: their buffer is their delay whatever the schedule.
    """

    graph: SdfGraph
    kind: str
    repetitions: dict[str, int]
    schedule: Schedule
    method: str
    buffers: list[tuple[SdfEdge, int]]
    self_loops: list[tuple[SdfEdge, int]]
    buffer_total: int
    sas_lower_bound: int
    edge_lower_bound: int
    flat_sas_total: int | None
    single_appearance: bool
    optimal: bool | None

    @property
    def schedule_text(self) -> str:
        """The schedule in looped notation (see ``schedule``)."""
        return self.schedule.text()

    @property
    def edge_bound_gap(self) -> int:
        """How far ``buffer_total`` is above the per-edge lower bound."""
        return self.buffer_total - self.edge_lower_bound

    def firings(self) -> Iterator[str]:
        """The schedule as a flat sequence of actor names, one per firing."""
        return self.schedule.firings()

    def run_length(self) -> list[tuple[str, int]]:
        """The schedule as ``(actor, consecutive firings)`` runs."""
        return self.schedule.run_length()

    def to_json_dict(self, name: str) -> dict:
        """The machine-readable summary (stable keys, see docs/sdf.md)."""
        result = {
            "name": name,
            "repetitions": dict(self.repetitions),
            "schedule": self.schedule_text,
            "buffers": [
                {"src": edge.src, "dst": edge.dst, "size": size} for edge, size in self.buffers
            ],
            "buffer_total": self.buffer_total,
            "sas_lower_bound": self.sas_lower_bound,
            "edge_lower_bound": self.edge_lower_bound,
        }
        if self.self_loops:
            result["self_loops"] = [
                {"src": edge.src, "dst": edge.dst, "size": size} for edge, size in self.self_loops
            ]
        return result

    def render_text(self, name: str) -> str:
        """A human-readable report with a table of buffers."""
        kind = SCHEDULE_NAMES[self.kind] + (" flat" if self.kind == "min-buffer" else "")
        if self.kind == "sas" and not self.single_appearance:
            kind = "looped (not single-appearance)"
        lines = [f"SDF analysis of {name}"]
        lines.append(
            "  repetitions: "
            + (", ".join(f"{actor}={count}" for actor, count in self.repetitions.items()) or "-")
        )
        lines.append(f"  schedule ({kind}, {self.method}):")
        text = self.schedule_text or "(empty)"
        if len(text) > _REPORT_SCHEDULE_CHARS:
            text = (
                text[:_REPORT_SCHEDULE_CHARS]
                + f" ... ({len(text) - _REPORT_SCHEDULE_CHARS} more characters)"
            )
        lines.append(f"    {text}")
        rows = [("edge", "rates", "delay", "buffer")]
        for edge, size in self.buffers + self.self_loops:
            note = " (self-loop)" if edge.is_self_loop else ""
            rows.append((edge.label + note, f"{edge.prod}:{edge.cons}", str(edge.delay), str(size)))
        widths = [max(len(row[i]) for row in rows) for i in range(4)]
        for i, row in enumerate(rows):
            lines.append(
                "    " + row[0].ljust(widths[0]) + "  "
                + "  ".join(cell.rjust(width) for cell, width in zip(row[1:], widths[1:]))
            )
            if i == 0:
                lines.append("    " + "-" * (sum(widths) + 6))
        lines.append(f"  buffer total: {self.buffer_total} tokens")
        bounds = [
            f"single-appearance lower bound {self.sas_lower_bound}",
            f"per-edge lower bound {self.edge_lower_bound}",
        ]
        if self.flat_sas_total is not None:
            bounds.append(f"flat SAS {self.flat_sas_total}")
        lines.append("  compare: " + ", ".join(bounds))
        if self.kind == "min-buffer":
            proof = {True: "optimal", False: "not proven optimal"}[bool(self.optimal)]
            lines.append(f"  gap to the per-edge lower bound: {self.edge_bound_gap} ({proof})")
        return "\n".join(lines) + "\n"


def analyze(
    graph: SdfGraph, schedule: str = "sas", options: SdfOptions | None = None
) -> Analysis:
    """Repetition vector, deadlock check, schedule and buffer sizes.

    ``schedule`` is ``"sas"`` (looped single-appearance schedule of least
    buffer memory found by APGAN/RPMC + DPPO), ``"flat"`` (flat
    single-appearance schedule: every actor's firings in one run) or
    ``"min-buffer"`` (flat schedule of least total buffer memory).  Raises
    InconsistentGraphError or DeadlockError for graphs that have no valid
    schedule, ScheduleError when the kind asked for has none.  The schedule
    is verified by simulation before it is returned.
    """
    if schedule not in SCHEDULE_KINDS:
        raise ValueError(f"schedule must be one of {', '.join(SCHEDULE_KINDS)}, not {schedule!r}")
    # the schedulers allocate hundreds of thousands of short-lived tuples and
    # lists (freed by reference counting, no cycles): on large graphs the
    # collector's passes over them cost about a tenth of the analysis
    with cycle_collection_paused():
        return _analyze(graph, schedule, options or SdfOptions())


def _analyze(graph: SdfGraph, schedule: str, options: SdfOptions) -> Analysis:
    ig = IndexedGraph.from_graph(graph)
    repetitions = compute_repetitions(ig)
    execute_iteration(ig, repetitions)

    flat = flat_sas(ig, repetitions)
    flat_total = None
    if flat is not None:
        flat_total = _total(ig, check_schedule(ig, flat, repetitions))
    if schedule == "flat":
        if flat is None:
            raise ScheduleError("this graph has no flat single-appearance schedule (a cycle of edges whose "
                                "initial tokens do not cover an iteration); use the sas or min-buffer schedule")
        chosen, method, single_appearance, optimal = flat, "topological order", True, None
    elif schedule == "sas":
        result = best_sas(ig, repetitions, options)
        chosen, method = result.schedule, result.method
        single_appearance, optimal = result.single_appearance, None
    else:
        firings = sum(repetitions)
        if firings > options.max_flat_firings:
            raise ScheduleError(
                f"a flat schedule of this graph has {firings} firings per iteration, more "
                f"than the limit of {options.max_flat_firings}; use the single-appearance schedule"
            )
        found = min_buffer_schedule(
            ig, repetitions, options.exact_max_firings, options.exact_max_evaluations
        )
        chosen = Schedule.from_runs((ig.names[a], count) for a, count in found.runs)
        method = found.method
        single_appearance, optimal = chosen.is_single_appearance, found.optimal

    sizes = check_schedule(ig, chosen, repetitions)
    buffers = [(ig.edges[e], sizes[e]) for e in range(ig.edge_count) if not ig.is_self_loop(e)]
    self_loops = [(ig.edges[e], sizes[e]) for e in range(ig.edge_count) if ig.is_self_loop(e)]
    return Analysis(
        graph=graph,
        kind=schedule,
        repetitions=dict(zip(ig.names, repetitions)),
        schedule=chosen,
        method=method,
        buffers=buffers,
        self_loops=self_loops,
        buffer_total=sum(size for _, size in buffers),
        sas_lower_bound=sas_lower_bound(graph),
        edge_lower_bound=edge_lower_bound(graph),
        flat_sas_total=flat_total,
        single_appearance=single_appearance,
        optimal=optimal,
    )


def _total(ig: IndexedGraph, sizes: list[int]) -> int:
    return sum(size for e, size in enumerate(sizes) if not ig.is_self_loop(e))
