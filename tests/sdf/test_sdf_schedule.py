"""Looped schedules: notation, flattening, and buffer simulation."""

import pytest

from easylab.analysis.sdf import Fire, Loop, Schedule, repeat, verify
from sdf_testlib import cd2dat, simulate

CD2DAT_SCHEDULE = Schedule((
    Loop(7, (Loop(7, (Loop(3, (Fire("A"), Fire("B"))), Fire("C", 2))), Fire("D", 4))),
    Loop(32, (Fire("E"), Fire("F", 5))),
))


def test_compact_notation_for_one_letter_names():
    assert CD2DAT_SCHEDULE.text() == "(7(7(3AB)(2C))(4D))(32E(5F))"
    assert str(CD2DAT_SCHEDULE) == CD2DAT_SCHEDULE.text()
    assert CD2DAT_SCHEDULE.text(compact=False) == "(7 (7 (3 A B) (2 C)) (4 D)) (32 E (5 F))"


def test_spaced_notation_for_longer_names():
    schedule = Schedule((Loop(7, (Loop(3, (Fire("src"), Fire("b"))), Fire("c", 2))),))
    assert schedule.text() == "(7 (3 src b) (2 c))"
    digits = Schedule((Fire("1", 2), Fire("2")))
    assert digits.text() == "(2 1) 2"


def test_textbook_cd2dat_schedule_buffers():
    graph = cd2dat()
    sizes = verify(graph, CD2DAT_SCHEDULE)
    assert [sizes[e] for e in graph.edges] == [1, 6, 28, 224, 5]
    assert sum(sizes.values()) == 264
    reps = {"A": 147, "B": 147, "C": 98, "D": 28, "E": 32, "F": 160}
    assert simulate(graph, CD2DAT_SCHEDULE.firings(), reps) == sizes


def test_flat_forms_and_counts():
    schedule = Schedule((Loop(2, (Fire("A"), Fire("B", 2))), Fire("B"), Loop(2, (Fire("C"),))))
    assert list(schedule.firings()) == ["A", "B", "B", "A", "B", "B", "B", "C", "C"]
    assert schedule.run_length() == [("A", 1), ("B", 2), ("A", 1), ("B", 3), ("C", 2)]
    assert schedule.firing_counts() == {"A": 2, "B": 5, "C": 2}
    assert schedule.appearances() == {"A": 1, "B": 2, "C": 1}
    assert not schedule.is_single_appearance
    assert Schedule.from_runs([("A", 1), ("A", 2), ("B", 1)]).body == (Fire("A", 3), Fire("B"))


def test_repeat_builds_minimal_nodes():
    assert repeat(1, [Fire("A")]) == [Fire("A")]
    assert repeat(3, [Fire("A", 2)]) == [Fire("A", 6)]
    assert repeat(2, [Loop(3, (Fire("A"), Fire("B")))]) == [Loop(6, (Fire("A"), Fire("B")))]
    assert repeat(2, [Fire("A"), Fire("B")]) == [Loop(2, (Fire("A"), Fire("B")))]


@pytest.mark.parametrize("make", [lambda: Fire("A", 0), lambda: Loop(0, (Fire("A"),)), lambda: Loop(2, ())])
def test_invalid_nodes(make):
    with pytest.raises(ValueError):
        make()


def test_deep_trees_need_no_recursion():
    depth = 5000
    node = Fire("A")
    for _ in range(depth):
        node = Loop(1, (node, Fire("B")))
    schedule = Schedule((node,))
    text = schedule.text()
    assert text.startswith("(1(1(1") and text.count("B") == depth
    assert schedule.firing_counts() == {"A": 1, "B": depth}
    assert schedule.run_length()[:2] == [("A", 1), ("B", depth)]
