"""Charts: evolution with continuation slots (docs/ir.md, "Charts").

The order of every effect is the generated C's (templates/model.c.j2):
at the first activation the initial step is entered; afterwards, slot by
slot, the active step's ``Step.time`` grows by the task period and the step
chooses its first enabled transition (guards on the latched copies); the
transitions every source of which chose them fire, exits first (in
transition order, each becoming the chart's last fired transition), then
entries; last, the ``run`` dataflows of the active steps, in step order.
Published activity changes at the deadline only.
"""

from __future__ import annotations

from typing import Callable

from ..ir.program import Action, Chart, Program
from . import values as V
from .exprs import ExprCompiler


class ChartRunner:
    """The run-time state of one chart: its slots (the step each parallel
    branch continues with, or None), the steps' elapsed times (ms), whether
    it has started, the published activity flags and the transition it
    fired last."""

    def __init__(self, program: Program, chart: Chart, task, run_dataflow: Callable[[int], None]):
        self.chart = chart
        self.task = task
        self.run_dataflow = run_dataflow
        self.slots: list[int | None] = [None] * chart.slots
        self.elapsed = [0] * len(chart.steps)
        self.started = False
        self.active = [False] * len(chart.steps)  # published at the deadline
        self.fired: int | None = None  # the transition fired last (docs/ir.md, "Charts"), None: none yet
        # The debugger's probe (kind name, a, b), where the firmware has
        # EL_DEBUG_PROBE: set by the engine when it serves a debug interface.
        self.probe: Callable[[str, int, int], None] | None = None
        compiler = ExprCompiler([s.slot for s in chart.steps])
        self._period_ms = chart.period_ms or 0

        def actions(acts: list[Action]):
            return [(a.target, compiler.compile(a.value, program.items[a.target].type)) for a in acts]
        self._entry = [actions(s.entry) for s in chart.steps]
        self._exit = [actions(s.exit) for s in chart.steps]
        guards = {t.id: compiler.compile(t.guard) for t in chart.transitions}
        # Per step, its outgoing transitions in declaration order, with the
        # other sources that must be active and the guard.
        self._choices = [[(t.id, [(chart.steps[o].slot, o) for o in t.sources if o != s.id], guards[t.id])
                          for t in chart.transitions if s.id in t.sources] for s in chart.steps]

    def run(self) -> None:
        """One activation of the chart, on its task's local copies."""
        chart, slots, elapsed, local, probe = self.chart, self.slots, self.elapsed, self.task.local, self.probe
        if probe:
            probe("chart", chart.id, 0)
        if not self.started:
            self.started = True
            initial = chart.steps[chart.initial]
            slots[initial.slot] = initial.id
            elapsed[initial.id] = 0
            self._act(self._entry[initial.id])
            if probe:
                probe("step", chart.id, initial.id)
        else:
            choice: list[int | None] = [None] * chart.slots
            for slot, step in enumerate(slots):
                if step is None:
                    continue
                if self._period_ms:
                    elapsed[step] = V.time_add(elapsed[step], self._period_ms)
                for transition, others, guard in self._choices[step]:
                    if all(slots[s] == o for s, o in others) and guard(local, elapsed, slots):
                        choice[slot] = transition
                        break
            firing = [t for t in chart.transitions
                      if all(choice[chart.steps[s].slot] == t.id for s in t.sources)]
            for t in firing:
                self.fired = t.id
                if probe:
                    probe("transition", chart.id, t.id)
                for s in t.sources:
                    self._act(self._exit[s])
                    slots[chart.steps[s].slot] = None
            for t in firing:
                for s in t.targets:
                    slots[chart.steps[s].slot] = s
                    elapsed[s] = 0
                    self._act(self._entry[s])
                    if probe:
                        probe("step", chart.id, s)
        for step in chart.steps:
            if slots[step.slot] == step.id:
                for dataflow in step.runs:
                    self.run_dataflow(dataflow)
        if probe:
            probe("chart_end", chart.id, 0)

    def publish(self) -> None:
        """The step activity as of now becomes the published one (deadline)."""
        self.active = [self.slots[s.slot] == s.id for s in self.chart.steps]

    def _act(self, actions) -> None:
        local = self.task.local
        for target, evaluate in actions:
            local[target][0] = evaluate(local, self.elapsed, self.slots)
