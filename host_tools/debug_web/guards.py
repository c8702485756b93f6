"""The transitions' guard values of the online mode.

Each guard is the IR's expression, compiled by local execution's
expression compiler (generator/interp/exprs.py: the generated C's
arithmetic), and evaluated on a snapshot's values: the items it reads, the
step times (``CHART.STEP.time``) and the chart's active steps
(``CHART.active``) as the snapshot has them. The page shows whether the
guard holds now; the chart's next evolution, which first adds one period
to the active step's time, can see it change.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..debug_map import DebugMap


@dataclass
class _Guard:
    evaluate: Callable[[dict, list, list], object]
    needs: list[int]  # the debug items it reads
    times: list[int | None]  # per step id, its CHART.STEP.time item
    active: int  # the chart's CHART.active item


class GuardValues:
    """Every transition's guard, by its element id in the drawing
    (``transition:CHART.N``)."""

    def __init__(self, guards: dict[str, _Guard]):
        self.guards = guards

    @classmethod
    def of_model(cls, model_path: Path, dmap: DebugMap) -> "GuardValues | None":
        """The guards of the model in `model_path`; None when the model is not
        the map's program (its item ids would not be the firmware's)."""
        from ...core.expr import refs
        from ...interp.exprs import ExprCompiler
        from ...pipeline import lower_file

        program, _ = lower_file(model_path)
        if program is None or program.program_id != dmap.program_id:
            return None
        guards: dict[str, _Guard] = {}
        for chart in program.charts:
            active = dmap.by_name.get(f"{chart.name}.active")
            times = [dmap.by_name.get(f"{chart.name}.{s.name}.time") for s in chart.steps]
            if active is None or None in times:
                continue
            compiler = ExprCompiler([s.slot for s in chart.steps])
            for tr in chart.transitions:
                needs = {active.id}
                for ref in refs(tr.guard):
                    needs.add(ref.target if ref.kind == "item" else
                              times[ref.target].id if ref.kind == "step_time" else active.id)
                guards[f"transition:{chart.name}.{tr.id}"] = _Guard(
                    compiler.compile(tr.guard), sorted(needs), [t.id for t in times], active.id)
        return cls(guards)

    def needs(self, element: str) -> list[int]:
        """The items a transition's guard reads (polled while it is in sight)."""
        guard = self.guards.get(element)
        return guard.needs if guard else []

    def evaluate(self, values: dict[int, object]) -> dict[str, bool]:
        """The value of every guard whose items are all in `values`."""
        out: dict[str, bool] = {}
        local = {i: v if isinstance(v, list) else [v] for i, v in values.items()}
        for element, g in self.guards.items():
            if any(i not in values for i in g.needs):
                continue
            times = [values.get(t, 0) for t in g.times]
            slots = local[g.active]
            out[element] = bool(g.evaluate(local, times, slots))
        return out
