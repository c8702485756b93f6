"""The dispatcher's widths from the program's timing (docs/ir.md,
"Dispatcher widths"): 16-bit ticks where every span the dispatcher compares
stays under 2^15 ticks and 2^15 ticks last at least 10 s, task masks as
wide as the tasks need; neither is part of the IR dump (the program id)."""

from __future__ import annotations

import pytest

from easylab.ir.program import TICK_16_HEADROOM_US, to_json
from easylab.pipeline import lower_file


def program_of(tmp_path, periods: list[str]):
    """A model with one task per period, each running its own dataflow."""
    text = "model widths\nimport std\n"
    for k, period in enumerate(periods):
        text += (f"var x{k}: uint8\ndataflow D{k} {{\n    c = Const<uint8>(value = 1)\n    c.y -> x{k}\n}}\n"
                 f"task t{k} period {period} {{ run D{k} }}\n")
    path = tmp_path / "widths.elab"
    path.write_text(text)
    program, result = lower_file(str(path))
    assert program is not None, result.report()
    return program


def test_a_1_ms_tick_under_2_15_ticks_of_hyperperiod_has_16_bit_ticks(tmp_path):
    p = program_of(tmp_path, ["1 ms", "30 s"])
    assert (p.tick_us, p.hyperperiod) == (1000, 30000)
    assert p.tick_bits == 16


def test_a_hyperperiod_of_2_15_ticks_or_more_keeps_32_bits(tmp_path):
    p = program_of(tmp_path, ["1 ms", "40 s"])
    assert p.hyperperiod == 40000 and p.tick_bits == 32


def test_a_short_tick_keeps_32_bits_for_the_lateness_headroom(tmp_path):
    """2^15 ticks of 250 us are 8.2 s, under the 10 s an instant may be late."""
    p = program_of(tmp_path, ["250 us"])
    assert p.hyperperiod == 1 and (1 << 15) * p.tick_us < TICK_16_HEADROOM_US
    assert p.tick_bits == 32
    assert program_of(tmp_path, ["400 us"]).tick_bits == 16


@pytest.mark.parametrize("tasks, bits", [(1, 8), (8, 8), (9, 16), (16, 16), (17, 32)])
def test_task_masks_are_as_wide_as_the_tasks_need(tmp_path, tasks, bits):
    assert program_of(tmp_path, ["10 ms"] * tasks).task_mask_bits == bits


def test_the_widths_are_not_part_of_the_program_id(tmp_path):
    dump = to_json(program_of(tmp_path, ["1 ms"]))
    assert "tick_bits" not in dump and "task_mask_bits" not in dump
