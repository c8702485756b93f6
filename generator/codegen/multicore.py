"""The C of a multi-core build (docs/multicore.md): what the plan of
ir/multicore.py decided, printed. Nothing here decides anything.

A dataflow the plan runs in parallel gets a flat single-appearance layout
(every edge holds one iteration's tokens after its delay ones, so every
token has its own place and no firing overwrites a token another core has
yet to read) and two codes over it: one per core, each running its list
of firings and waiting, before a firing, for the firing of another core
it follows (a flag per awaited firing holding the iteration's epoch:
C11 release on the writer's side, acquire on the reader's), and one
sequential code in single-core schedule order, used while the cores run
a group of tasks. Both leave the same values, so which one runs never
shows in a trace.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from ..ir.multicore import FiringPlan, MulticorePlan
from ..ir.program import Fire, Schedule
from .c_syntax import ident

JOB_TASKS = 0  # the job "run the group's tasks on their cores"; dataflow jobs follow
NO_CORE = 0xFF


@dataclass
class MulticoreView:
    """What the templates print in a multi-core build."""

    cores: int
    job_tasks: int = JOB_TASKS
    functions: list[tuple[str, list[str]]] = field(default_factory=list)  # (signature, body lines)
    declarations: list[str] = field(default_factory=list)
    jobs: list[tuple[int, str]] = field(default_factory=list)  # (job, call with el_core)
    groups: list[tuple[int, list[int]]] = field(default_factory=list)  # (release mask, core per task or NO_CORE)


def dataflow_functions(builder, fp: FiringPlan, job: int, view: MulticoreView) -> list[str]:
    """Declare the buffers and code of a parallel dataflow; returns the body
    of its function (called by its task)."""
    df = fp.dataflow
    counts: dict[str, int] = {}
    for node, _ in fp.firings:
        counts[node] = counts.get(node, 0) + 1
    flat = replace(df, schedule=Schedule(tuple(Fire(node, n) for node, n in counts.items())))
    layout = builder.layout(flat)
    name = f"el_df{df.id}_{ident(df.name)}"
    waits = fp.cross_waits()
    awaited = sorted({p for _, p in waits})
    flag = {f: k for k, f in enumerate(awaited)}
    waits_before: dict[int, list[int]] = {}
    for f, p in waits:
        waits_before.setdefault(f, []).append(p)
    # Without a wait across cores (independent firings) there is no epoch to keep.
    if awaited:
        view.declarations += [f"static uint32_t {name}_epoch; /* iterations run on the cores */",
                              f"static el_mc_flag_t {name}_done[{len(awaited)}]; "
                              f"/* the epoch of the firings other cores wait for */"]
    per_core = ([f"    const uint32_t el_epoch = {name}_epoch;"] if awaited else []) + ["    switch (el_core) {"]
    uses_loop = False
    for core, order in enumerate(fp.order):
        if not order:
            continue
        per_core.append(f"    case {core}u:")
        body, looped = _firings(builder, layout, fp, order, "        ", waits_before, flag, name)
        uses_loop |= looped
        per_core += body + ["        break;"]
    per_core += ["    default: break;", "    }"]
    if uses_loop:
        per_core.insert(0, "    uint16_t el_r;")
    view.functions.append((f"static void {name}_core(uint8_t el_core)", per_core))
    view.jobs.append((job, f"{name}_core(el_core);"))
    sequential, looped = _firings(builder, layout, fp, list(range(len(fp.firings))), "        ", {}, {}, name)
    body = (["    uint16_t el_r;"] if looped else []) + ["    if (el_mc_serial) { /* the cores run a group of tasks */"]
    body += sequential
    body += ["    } else {"]
    if awaited:  # 0 is the flags' value before any iteration: never an epoch
        body.append(f"        {name}_epoch = ({name}_epoch == UINT32_MAX) ? 1u : {name}_epoch + 1u;")
    body += [f"        el_threads_run({job}u);", "    }"]
    return body + builder.top_level_shifts(layout)


def _firings(builder, layout, fp: FiringPlan, order: list[int], ind: str, waits_before: dict[int, list[int]],
             flag: dict[int, int], name: str) -> tuple[list[str], bool]:
    """The code of ``order``'s firings: consecutive firings of one node with
    no wait or post between them as one loop. Returns (lines, uses el_r)."""
    lines: list[str] = []
    looped = False
    i = 0
    while i < len(order):
        f = order[i]
        node, k = fp.firings[f]
        j = i
        while (j + 1 < len(order) and fp.firings[order[j + 1]] == (node, fp.firings[order[j]][1] + 1)
               and order[j] not in flag and order[j + 1] not in waits_before):
            j += 1
        for p in waits_before.get(f, []):
            lines.append(f"{ind}el_mc_wait(&{name}_done[{flag[p]}u], el_epoch); /* {_label(fp, p)} on core "
                         f"{fp.core[p]} */")
        if j == i:
            builder.fire_one(layout, node, f"{k}u", ind, lines)
        else:
            looped = True
            last = fp.firings[order[j]][1]
            lines.append(f"{ind}for (el_r = {k}u; el_r <= {last}u; el_r++) {{")
            builder.fire_one(layout, node, "el_r", ind + "    ", lines)
            lines.append(f"{ind}}}")
        if order[j] in flag:
            lines.append(f"{ind}el_mc_post(&{name}_done[{flag[order[j]]}u], el_epoch); /* {_label(fp, order[j])} */")
        i = j + 1
    return lines, looped


def _label(fp: FiringPlan, f: int) -> str:
    node, k = fp.firings[f]
    return f"{node}#{k}"


def group_table(plan: MulticorePlan, task_count: int, view: MulticoreView) -> None:
    """The groups of tasks released together that run on several cores."""
    for g in plan.groups:
        if g.parallel:
            view.groups.append((g.mask, [g.core.get(t, NO_CORE) for t in range(task_count)]))
