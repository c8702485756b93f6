"""The transition each chart fired last (docs/ir.md, "Charts") in local
execution across a live replacement: kept with the chart's state when the
new model's transitions are the same (by their steps' names, in order),
none when they differ (a number would name another transition), and gone
with a chart that restarts."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from easylab.interp.charts import ChartRunner
from easylab.interp.replacement import Replacement, _transfer_charts
from interp_testlib import DATA, lower

LIVE = (DATA / "live.elab").read_text()


def _state(program) -> SimpleNamespace:
    """The charts of a program state, as the replacement sees them."""
    return SimpleNamespace(charts=[ChartRunner(program, c, None, lambda dataflow: None) for c in program.charts])


@pytest.mark.parametrize("edit, kept, fired", [
    (lambda text: text.replace("smooth > 200", "smooth > 300"), True, 1),  # a guard changed: the same transitions
    (lambda text: text.replace("    transition Low  -> High when smooth > 200\n", "")
                      .replace("    transition High -> Low  when smooth < 100\n",
                               "    transition High -> Low  when smooth < 100\n"
                               "    transition Low  -> High when smooth > 200\n"), True, None),  # reordered
    (lambda text: text.replace("step High", "step Upper").replace("-> High", "-> Upper")
                      .replace("High ->", "Upper ->"), False, None),  # a renamed step: the chart restarts
])
def test_the_last_fired_transition_across_a_replacement(edit, kept, fired, tmp_path):
    old_program = lower(_write(tmp_path / "live.elab", LIVE))
    new_program = lower(_write(tmp_path / "edited.elab", edit(LIVE)))
    old, new = _state(old_program), _state(new_program)
    runner = old.charts[0]
    runner.started, runner.slots, runner.fired = True, [0], 1  # in Low, back from High (High -> Low fired)
    report = Replacement(0, old_program.program_id, new_program.program_id)
    _transfer_charts(old, new, report)
    assert (report.kept_charts == ["Mode"]) == kept
    assert new.charts[0].fired == fired


def _write(path, text):
    path.write_text(text)
    return path
