"""The interpreter's runner (generator/interp/runner.c) on its own: the
widening copies against the C assignment of values.py, the bounds of
channel rings and staging arrays, the guards of deadlines, and the
dispatch table's stretches."""

from __future__ import annotations

import ctypes

import pytest

from easylab.core import types as T
from easylab.interp import PluginCache
from easylab.interp import runner as R
from easylab.interp import values as V


@pytest.fixture(scope="module")
def runner(tmp_path_factory) -> R.Runner:
    return PluginCache(tmp_path_factory.mktemp("runner_cache")).runner


def _array(t: T.ValueType, values: list):
    return (V.ctype(t) * len(values))(*values)


def _run(runner: R.Runner, ops: list[R.Op]) -> R.Cursor:
    plan, cursor = R.OpList(ops), R.Cursor()
    runner.run(plan.all, cursor)
    return cursor


WIDENINGS = [(a, b) for a in T.SCALARS.values() for b in T.SCALARS.values()
             if a != b and a.is_numeric and T.widens(a, b)]


@pytest.mark.parametrize("src, dst", WIDENINGS, ids=[f"{a.name}-{b.name}" for a, b in WIDENINGS])
def test_widening_is_the_c_assignment(runner, src, dst):
    values = sorted({src.min, src.min + 1, -1 if src.signed else 1, 0, 1, src.max - 1, src.max})
    source = _array(src, values)
    target = _array(dst, [V.zero(dst)] * len(values))
    _run(runner, [R.copy(ctypes.addressof(target), dst, ctypes.addressof(source), src, len(values))])
    assert list(target) == [V.store(dst)(v) for v in values]


def test_copies_overlap_like_memmove(runner):
    """The delay tokens of an edge move to its front: source and
    destination may overlap."""
    tokens = _array(T.INT16, [1, 2, 3, 4, 5])
    _run(runner, [R.copy(ctypes.addressof(tokens), T.INT16, ctypes.addressof(tokens) + 2, T.INT16, 4)])
    assert list(tokens) == [2, 3, 4, 5, 5]


def test_ring_keeps_its_bounds(runner):
    ring = R.Ring(T.INT16, 3, [7])
    out, into = R.Stage(T.INT16, 2), R.Stage(T.INT16, 2)
    out.data[:] = [8, 9]
    _run(runner, [R.push(ring, out)])
    assert ring.tokens() == [7, 8, 9]
    with pytest.raises(R.RunnerFault) as err:  # two more do not fit
        _run(runner, [R.push(ring, out)])
    assert (err.value.kind, err.value.at) == (R.RING_FULL, ring.address)
    assert ring.tokens() == [7, 8, 9]
    _run(runner, [R.take(ring, into)])
    assert into.values() == [7, 8] and ring.tokens() == [9]
    with pytest.raises(R.RunnerFault) as err:  # one left, two wanted
        _run(runner, [R.take(ring, into)])
    assert err.value.kind == R.RING_EMPTY and ring.tokens() == [9]
    _run(runner, [R.push(ring, out), R.take(ring, into)])  # around the end of the array
    assert into.values() == [9, 8] and ring.tokens() == [9]


def test_ring_grows_for_tokens_from_python():
    """A replacement may bring more tokens than the channel's traffic
    leaves: the ring keeps room for both."""
    ring = R.Ring(T.INT8, 2, [1, 2])
    ring.extend([3, 4, 5])
    assert ring.tokens() == [1, 2, 3, 4, 5] and ring.struct.capacity >= 5 + 2
    ring.replace([6])
    assert ring.tokens() == [6]


def test_stage_cursor_keeps_its_bounds(runner):
    stage = R.Stage(T.INT16, 2)
    stage.data[:] = [-3, 4]
    edge = _array(T.INT32, [0, 0, 0])
    at = ctypes.addressof(edge)
    _run(runner, [R.read(stage, at, T.INT32, False), R.read(stage, at + 4, T.INT32, True),
                  R.read(stage, at + 8, T.INT32, True)])
    assert list(edge) == [-3, -3, 4]
    with pytest.raises(R.RunnerFault) as err:
        _run(runner, [R.read(stage, at, T.INT32, True)])  # the cursor is past both tokens
    assert (err.value.kind, err.value.at) == (R.STAGE, stage.address)
    _run(runner, [R.rewind(stage), R.write(stage, at + 8, T.INT32)])
    assert stage.values() == [4, 4]


def test_publication_needs_a_release(runner):
    flag, counter, when = ctypes.c_uint8(0), ctypes.c_uint64(0), ctypes.c_uint64(0)
    src, dst = _array(T.INT16, [5]), _array(T.INT16, [0])
    publish = [R.publish(ctypes.addressof(flag), 1),
               R.copy(ctypes.addressof(dst), T.INT16, ctypes.addressof(src), T.INT16, 1)]
    _run(runner, publish)
    assert dst[0] == 0  # not released: nothing published
    cursor = R.Cursor()
    cursor.now_us = 1234
    plan = R.OpList([R.release(ctypes.addressof(counter), ctypes.addressof(when)),
                     R.pending(ctypes.addressof(flag))])
    runner.run(plan.all, cursor)
    assert (counter.value, when.value, flag.value) == (1, 1234, 1)
    _run(runner, publish)
    assert dst[0] == 5 and flag.value == 0
    with pytest.raises(R.RunnerFault) as err:  # a guard that would skip past its list
        _run(runner, [R.publish(ctypes.addressof(flag), 5)])
    assert err.value.kind == R.BAD_OP


def test_a_called_list_calls_nothing(runner):
    stage = R.Stage(T.INT8, 1)
    inner = R.OpList([R.rewind(stage)])
    middle = R.OpList([R.call(inner)])
    _run(runner, [R.call(inner), R.call(inner)])
    with pytest.raises(R.RunnerFault) as err:
        _run(runner, [R.call(middle)])
    assert err.value.kind == R.NESTED


def test_stretches_of_the_table(runner):
    """Instants run while native, before the limit time and within the
    count; the table repeats hyperperiod after hyperperiod."""
    counter, when = ctypes.c_uint64(0), ctypes.c_uint64(0)
    tick = [R.release(ctypes.addressof(counter), ctypes.addressof(when))]
    table = R.Table([tick, tick, tick], [0, 2, 3], [True, True, False], hyperperiod=5, tick_us=1000)
    cursor = R.Cursor()
    assert runner.run_instants(table, cursor, 2 ** 64 - 1, 10, 100) == 2  # the third needs Python
    assert (counter.value, when.value, cursor.index, cursor.now_us) == (2, 2000, 2, 2000)
    cursor.index = 0
    cursor.base = 5  # the next hyperperiod
    assert runner.run_instants(table, cursor, 7000, 10, 100) == 1  # the one at 7 ms is not before 7 ms
    assert (cursor.index, cursor.now_us) == (1, 5000)
    table = R.Table([tick, tick], [0, 2], [True, True], hyperperiod=4, tick_us=10)
    cursor = R.Cursor()
    assert runner.run_instants(table, cursor, 2 ** 64 - 1, 5, 100) == 5
    assert (cursor.base, cursor.index, cursor.now_us) == (8, 1, 80)
    assert runner.run_instants(table, cursor, 2 ** 64 - 1, 100, 3) == 3  # the work limit, in operations
