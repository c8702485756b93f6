"""A task whose dataflows read and write no item (no var, param, channel or
device datum: actors only) still builds warning-free: it has no local copy
(an empty one, never used, failed the build on -Wunused-variable)."""

from __future__ import annotations

from native_testlib import build, run

MODEL = """\
model quiet
import std
dataflow D {
    k = Const<int8>(value = 1)
    g = Gain<int8>()
    k.y -> g.x
}
task main period 1 ms { run D }
"""


def test_a_task_without_items_builds_and_runs(tmp_path):
    model = tmp_path / "quiet.elab"
    model.write_text(MODEL, encoding="utf-8")
    exe = build(model, tmp_path / "build")
    result = run(exe, tmp_path / "trace.csv", duration="10ms")
    assert result.trace_text.splitlines()[0] == "time_us"
