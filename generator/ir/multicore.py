"""Multi-core plans of a lowered program (docs/multicore.md).

Two kinds of parallelism, both decided here, from the IR alone, before any
C is generated:

* **Firings of a dataflow.** One iteration of a dataflow is a precedence
  graph of firings: the ``k``-th firing of an actor follows its
  ``(k-1)``-th (an actor has state), and follows the firings that produced
  the tokens it takes (the token stream of an edge within one iteration:
  the ``delay`` initial tokens first, then the producer's firings in
  order). Firings that touch the task's local copy (external endpoints,
  actors with runtime arguments) and firings of actor types with
  file-scope code keep their single-core order among themselves. The graph
  is list-scheduled on the cores (highest bottom level first, earliest
  start, ties by schedule order and core number): every core runs its
  list in order and waits only for the predecessors placed on other cores.
* **LET tasks released at the same instant.** A task reads its inputs at
  release and publishes at its deadline, so tasks released together share
  nothing while they run: each group of such tasks is placed on the cores
  (longest first, least-loaded core).

Costs are integers (nanoseconds per firing): measured by a profiling run
(``profile``), declared, or a default. Everything is integer arithmetic
in a fixed order, so the same program gives the same plan every time.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass, field

from .program import Dataflow, Program

# A firing without a measured or declared cost (ns); an external endpoint
# (a copy between the task's local copy and a buffer).
DEFAULT_FIRING_NS = 100
ENDPOINT_NS = 10
# A chart's evolution when a task's cost is estimated for placement (ns).
CHART_NS = 200
# What one parallel run costs beyond its firings: posting the job to the
# other cores and joining them (ns), and each wait of one core for another.
PARALLEL_RUN_NS = 10_000
CROSS_WAIT_NS = 300
# Above this many firings per iteration a dataflow stays on one core (the
# parallel code has one statement per firing run).
MAX_FIRINGS = 4096


@dataclass
class FiringPlan:
    """One dataflow's iteration on ``cores`` cores."""

    dataflow: Dataflow
    cores: int
    firings: list[tuple[str, int]]  # (node, index within the iteration), in single-core schedule order
    preds: list[tuple[int, ...]]  # per firing: the firings it follows (indices into ``firings``)
    cost: list[int]  # ns per firing
    core: list[int]  # per firing
    start: list[int]  # predicted start (ns from the iteration's start)
    order: list[list[int]]  # per core: its firings in the order it runs them
    parallel: bool  # the generated code runs it on the cores
    reason: str  # why (or why not)

    @property
    def sequential_ns(self) -> int:
        return sum(self.cost)

    @property
    def makespan_ns(self) -> int:
        return max((s + c for s, c in zip(self.start, self.cost)), default=0)

    @property
    def critical_path_ns(self) -> int:
        return max(_bottom_levels(self.preds, self.cost), default=0)

    def cross_waits(self) -> list[tuple[int, int]]:
        """(waiting firing, firing waited for): the predecessors on other
        cores not already covered by an earlier wait of the same core (a
        core runs its list in order, so a wait for a firing covers the
        ones before it on its core)."""
        position = {f: i for lst in self.order for i, f in enumerate(lst)}
        waits = []
        for lst in self.order:
            covered: dict[int, int] = {}  # other core -> the last position of it waited for
            for f in lst:
                latest: dict[int, int] = {}
                for p in self.preds[f]:
                    c = self.core[p]
                    if c != self.core[f] and position[p] > covered.get(c, -1) \
                            and (c not in latest or position[p] > position[latest[c]]):
                        latest[c] = p
                for c in sorted(latest):
                    waits.append((f, latest[c]))
                    covered[c] = position[latest[c]]
        return sorted(waits)

    @property
    def used_cores(self) -> int:
        return sum(1 for lst in self.order if lst)

    def predicted_ns(self) -> int:
        """The predicted time of one iteration on the cores: the makespan,
        the cost of a parallel run and of each wait across cores (one
        core: the sum of the costs)."""
        if self.used_cores < 2:
            return self.sequential_ns
        return self.makespan_ns + PARALLEL_RUN_NS + CROSS_WAIT_NS * len(self.cross_waits())

    def chosen_ns(self) -> int:
        """The predicted time of one iteration as the generated code runs it."""
        return self.predicted_ns() if self.parallel else self.sequential_ns

    def summary(self) -> dict:
        """The JSON object of ``easylab analyze --cores N --json`` for this dataflow."""
        return {
            "name": self.dataflow.name,
            "cores": self.cores,
            "firings": len(self.firings),
            "sequential_ns": self.sequential_ns,
            "makespan_ns": self.makespan_ns,
            "critical_path_ns": self.critical_path_ns,
            "predicted_ns": self.predicted_ns(),
            "speedup": round(self.sequential_ns / self.predicted_ns(), 2) if self.predicted_ns() else None,
            "cross_core_waits": len(self.cross_waits()),
            "parallel": self.parallel,
            "reason": self.reason,
            "schedule": [[{"firing": _label(self.firings[f]), "start_ns": self.start[f], "cost_ns": self.cost[f]}
                          for f in lst] for lst in self.order],
        }

    def render_text(self) -> str:
        s = self.summary()
        lines = [f"dataflow {s['name']} on {self.cores} cores: {s['firings']} firings per iteration, "
                 f"{s['sequential_ns']} ns on one core; on {self.cores}: makespan {s['makespan_ns']} ns "
                 f"(critical path {s['critical_path_ns']} ns), predicted {s['predicted_ns']} ns with "
                 f"{s['cross_core_waits']} waits across cores (speedup {s['speedup']:.2f})",
                 f"  {'parallel' if self.parallel else 'single core'}: {self.reason}"]
        for c, lst in enumerate(self.order):
            runs = _runs([self.firings[f] for f in lst])
            lines.append(f"  core {c}: " + (" ".join(runs) or "-"))
        return "\n".join(lines) + "\n"


@dataclass
class TaskGroup:
    """Tasks released at the same instants, placed on the cores."""

    tasks: list[int]  # task ids, ascending
    names: list[str]
    cost: dict[int, int]  # ns per task
    core: dict[int, int]  # task id -> core
    parallel: bool
    reason: str

    @property
    def mask(self) -> int:
        return sum(1 << t for t in self.tasks)

    def loads(self, cores: int) -> list[int]:
        loads = [0] * cores
        for t in self.tasks:
            loads[self.core[t]] += self.cost[t]
        return loads

    def summary(self, cores: int) -> dict:
        return {"tasks": self.names, "cores": [self.core[t] for t in self.tasks],
                "cost_ns": [self.cost[t] for t in self.tasks], "loads_ns": self.loads(cores),
                "parallel": self.parallel, "reason": self.reason}


@dataclass
class MulticorePlan:
    """Every dataflow's firing plan and every group of tasks released together."""

    cores: int
    dataflows: list[FiringPlan]
    groups: list[TaskGroup] = field(default_factory=list)

    @property
    def parallel(self) -> bool:
        """Whether anything runs on more than one core (else: a single-core build)."""
        return self.cores > 1 and (any(p.parallel for p in self.dataflows) or any(g.parallel for g in self.groups))

    def summary(self) -> dict:
        return {"cores": self.cores, "parallel": self.parallel,
                "dataflows": [p.summary() for p in self.dataflows],
                "task_groups": [g.summary(self.cores) for g in self.groups]}

    def notes(self, single_core: str = "a single-core build") -> list[str]:
        """One line per dataflow and task group saying whether it runs on
        the cores and why, then the verdict when nothing does."""
        on = f"on {self.cores} cores"
        notes = [f"dataflow {p.dataflow.name}: {on if p.parallel else 'one core'} ({p.reason})"
                 for p in self.dataflows]
        notes += [f"tasks {', '.join(g.names)}: {on if g.parallel else 'one core'} ({g.reason})"
                  for g in self.groups]
        if not self.parallel:
            notes.append(f"{self.cores} cores: nothing pays on more than one core: {single_core}")
        return notes

    def render_text(self) -> str:
        out = [p.render_text() for p in self.dataflows]
        for g in self.groups:
            placed = ", ".join(f"{n} on core {g.core[t]}" for t, n in zip(g.tasks, g.names))
            out.append(f"tasks released together: {placed}\n  {'parallel' if g.parallel else 'single core'}: "
                       f"{g.reason}\n")
        verdict = ("some parts run in parallel" if self.parallel
                   else "nothing pays on more than one core: a single-core build")
        out.append(f"{self.cores} cores: {verdict}\n")
        return "\n".join(out)


# ====================================================================== building plans


def plan(program: Program, cores: int, costs: dict[str, int] | None = None, always: bool = False) -> MulticorePlan:
    """The multi-core plan of ``program`` on ``cores`` cores. ``costs``: ns
    per firing by ``"dataflow.node"`` (a profile) or by actor type name
    (declared); ``always``: run in parallel whatever the prediction (tests)."""
    if cores < 1:
        raise ValueError("cores must be at least 1")
    costs = costs or {}
    flows = [firing_plan(program, df, cores, costs, always) for df in program.dataflows]
    groups = task_groups(program, cores, flows, costs, always)
    return MulticorePlan(cores, flows, groups)


def firing_plan(program: Program, df: Dataflow, cores: int, costs: dict[str, int], always: bool = False) -> FiringPlan:
    """The precedence graph of one iteration of ``df``, list-scheduled on ``cores``."""
    firings, preds = precedence_graph(program, df)
    cost = [firing_cost(program, df, node, costs) for node, _ in firings]
    if len(firings) > MAX_FIRINGS:
        core, start, order = _one_core(cost, cores)
        return FiringPlan(df, cores, firings, preds, cost, core, start, order, False,
                          f"{len(firings)} firings per iteration, more than {MAX_FIRINGS}: kept on one core")
    core, start, order = list_schedule(preds, cost, cores)
    fp = FiringPlan(df, cores, firings, preds, cost, core, start, order, False, "")
    gain = fp.sequential_ns - fp.predicted_ns()
    if cores == 1:
        fp.reason = "one core"
    elif fp.used_cores < 2:
        fp.reason = "no two firings can run at once"
    elif always:
        fp.parallel, fp.reason = True, "parallel on request"
    elif gain <= 0:
        fp.reason = (f"parallel does not pay: {fp.predicted_ns()} ns on {cores} cores (synchronisation included) "
                     f"against {fp.sequential_ns} ns on one")
    else:
        fp.parallel, fp.reason = True, f"saves {gain} ns per iteration"
    return fp


def precedence_graph(program: Program, df: Dataflow) -> tuple[list[tuple[str, int]], list[tuple[int, ...]]]:
    """The firings of one iteration in single-core schedule order, and
    each firing's predecessors (see the module's docstring)."""
    order = list(df.schedule.firings())
    firings: list[tuple[str, int]] = []
    seen: dict[str, int] = {}
    index: dict[tuple[str, int], int] = {}
    for node in order:
        k = seen.get(node, 0)
        seen[node] = k + 1
        index[(node, k)] = len(firings)
        firings.append((node, k))
    preds: list[set[int]] = [set() for _ in firings]
    for f, (node, k) in enumerate(firings):
        if k > 0:
            preds[f].add(index[(node, k - 1)])
    for b in df.buffers:
        if b.src == b.dst:
            continue  # a self-loop: the actor's own order covers it
        d = len(b.initial)
        for j in range(seen.get(b.dst, 0)):
            first, last = j * b.cons - d, (j + 1) * b.cons - 1 - d  # token positions after the delay ones
            if last < 0:
                continue
            for i in range(max(first, 0) // b.prod, last // b.prod + 1):
                preds[index[(b.dst, j)]].add(index[(b.src, i)])
    # State outside the buffers: a firing that writes a place follows every
    # earlier firing that reads or writes it; one that reads it follows
    # the earlier ones that write it (single-core order otherwise).
    accesses: list[tuple[int, frozenset, frozenset]] = []
    for f, (node, _) in enumerate(firings):
        reads, writes = _accesses(program, df, node)
        if not reads and not writes:
            continue
        for g, r, w in accesses:
            if _meet(writes, r | w) or _meet(reads, w):
                preds[f].add(g)
        accesses.append((f, reads, writes))
    return firings, [tuple(sorted(p)) for p in preds]


ANY = "*"  # a read of any item of the task's local copy (a runtime argument's expression)


def _meet(a: frozenset, b: frozenset) -> bool:
    return bool(a & b) or (bool(a) and ANY in b) or (bool(b) and ANY in a)


def _accesses(program: Program, df: Dataflow, node: str) -> tuple[frozenset, frozenset]:
    """What a firing of ``node`` reads and writes beyond its buffers: the
    task's local copy (endpoints; runtime arguments read it), the
    file-scope code of its actor type (read and written)."""
    ext = next((e for e in df.externals if e.node == node), None)
    if ext is not None:
        place = frozenset({(ext.kind, ext.target)})  # one local copy per item, read and written
        return (place, frozenset()) if ext.direction == "in" else (frozenset(), place)
    inst = _instance(program, df, node)
    spec = program.specs[inst.spec]
    shared = frozenset({("impl", spec.type_name)}) if spec.impl is not None else frozenset()
    return (shared | (frozenset({ANY}) if inst.runtime_args else frozenset())), shared


def _instance(program: Program, df: Dataflow, node: str):
    return next(program.instances[i] for i in df.instances if program.instances[i].name == node)


def firing_cost(program: Program, df: Dataflow, node: str, costs: dict[str, int]) -> int:
    """ns of one firing of ``node``: measured (``"dataflow.node"``), declared
    (actor type name), else the default."""
    measured = costs.get(f"{df.name}.{node}")
    if measured is not None:
        return max(int(measured), 1)
    if any(e.node == node for e in df.externals):
        return ENDPOINT_NS
    spec = program.specs[_instance(program, df, node).spec]
    declared = costs.get(spec.type_name, spec.cost_ns)
    return max(int(declared), 1) if declared is not None else DEFAULT_FIRING_NS


def list_schedule(preds: list[tuple[int, ...]], cost: list[int], cores: int
                  ) -> tuple[list[int], list[int], list[list[int]]]:
    """List scheduling: of the ready firings, the one with the longest
    path to the end (bottom level) first, ties by index; on the core where
    it starts earliest, ties by core number. Returns (core, start, order)."""
    n = len(cost)
    level = _bottom_levels(preds, cost)
    succs: list[list[int]] = [[] for _ in range(n)]
    waiting = [len(p) for p in preds]
    for f, ps in enumerate(preds):
        for p in ps:
            succs[p].append(f)
    ready = [(-level[f], f) for f in range(n) if not preds[f]]
    heapq.heapify(ready)
    core, start, finish = [0] * n, [0] * n, [0] * n
    free = [0] * cores
    order: list[list[int]] = [[] for _ in range(cores)]
    while ready:
        _, f = heapq.heappop(ready)
        earliest = max((finish[p] for p in preds[f]), default=0)
        c = min(range(cores), key=lambda k: (max(free[k], earliest), k))
        core[f], start[f] = c, max(free[c], earliest)
        finish[f] = free[c] = start[f] + cost[f]
        order[c].append(f)
        for s in succs[f]:
            waiting[s] -= 1
            if waiting[s] == 0:
                heapq.heappush(ready, (-level[s], s))
    return core, start, order


def _bottom_levels(preds: list[tuple[int, ...]], cost: list[int]) -> list[int]:
    """Per firing: its cost plus the longest path after it (firings are in
    a topological order: the single-core schedule's)."""
    level = list(cost)
    for f in range(len(cost) - 1, -1, -1):
        for p in preds[f]:
            level[p] = max(level[p], cost[p] + level[f])
    return level


def _one_core(cost: list[int], cores: int) -> tuple[list[int], list[int], list[list[int]]]:
    start, t = [], 0
    for c in cost:
        start.append(t)
        t += c
    return [0] * len(cost), start, [list(range(len(cost)))] + [[] for _ in range(cores - 1)]


def task_groups(program: Program, cores: int, flows: list[FiringPlan], costs: dict[str, int],
                always: bool = False) -> list[TaskGroup]:
    """The sets of tasks released at the same instant (more than one),
    each placed longest first on the least-loaded core."""
    flow_ns = {p.dataflow.id: p.sequential_ns for p in flows}
    masks = sorted({tuple(sorted(i.release)) for i in program.instants if len(i.release) > 1})
    groups = []
    for tasks in masks:
        cost = {t: sum(flow_ns[i] if kind == "dataflow" else CHART_NS for kind, i in program.tasks[t].runs) or 1
                for t in tasks}
        loads = [0] * cores
        core = {}
        for t in sorted(tasks, key=lambda t: (-cost[t], t)):
            c = min(range(cores), key=lambda k: (loads[k], k))
            core[t] = c
            loads[c] += cost[t]
        saved = sum(cost.values()) - max(loads) - PARALLEL_RUN_NS
        if cores == 1:
            parallel, reason = False, "one core"
        elif always:
            parallel, reason = True, "parallel on request"
        elif saved <= 0:
            parallel, reason = False, (f"parallel does not pay: {sum(cost.values())} ns on one core, "
                                       f"{max(loads) + PARALLEL_RUN_NS} ns on {cores} (synchronisation included)")
        else:
            parallel, reason = True, f"saves {saved} ns per release"
        groups.append(TaskGroup(list(tasks), [program.tasks[t].name for t in tasks], cost, core, parallel, reason))
    return groups


def _label(firing: tuple[str, int]) -> str:
    return f"{firing[0]}#{firing[1]}"


def _runs(firings: list[tuple[str, int]]) -> list[str]:
    """``A#0..3 B#0``: consecutive firings of one node in one piece."""
    out: list[str] = []
    i = 0
    while i < len(firings):
        node, k = firings[i]
        j = i
        while j + 1 < len(firings) and firings[j + 1] == (node, firings[j][1] + 1):
            j += 1
        out.append(f"{node}#{k}" if j == i else f"{node}#{k}..{firings[j][1]}")
        i = j + 1
    return out
