"""The interfaces library of local execution (generator/interp/interfaces.py):
what the debug and service suites (tests/debug, tests/service: board
`interp`) do not see from outside."""

from __future__ import annotations

import ctypes

from easylab.interp import PluginCache
from easylab.interp.interfaces import Interfaces, Library
from interp_testlib import DATA, EXAMPLES, lower


def test_a_program_loaded_again_gets_fresh_storage():
    """A program that comes back (replaced, then sent again) gets a library
    with zeroed actor state and its own links, not the earlier copy."""
    program = lower(EXAMPLES / "cd_to_dat.elab")
    cache = PluginCache()
    first, again = Interfaces(Library(program, cache)), Interfaces(Library(program, cache))
    (at_first, size), (at_again, size_again) = first.actor_states[1], again.actor_states[1]
    assert at_first != at_again and size == size_again == 4  # Stage: uint32_t acc
    ctypes.memset(at_first, 0xAB, size)
    assert ctypes.string_at(at_again, size) == bytes(size)
    first.items[0][0] = 7
    assert again.items[0][0] == 0
    assert first.library.path == again.library.path and len(list(first.library.directory.glob("*.so"))) == 1


def test_items_go_in_and_out_as_the_interpreter_holds_them():
    """push/pull keep the C copies and the interpreter's published values
    equal (a float32 as C holds it), and a pull replaces only what a client
    changed."""
    program = lower(DATA / "multirate.elab")
    io = Interfaces(Library(program, PluginCache()))
    floats = [k for k, i in enumerate(program.items) if i.type.name == "float32"]
    assert floats
    published = [[0.1 if k in floats else 0] * i.count for k, i in enumerate(program.items)]
    io.push(published, [])
    io.pull(published)
    for k in floats:  # 0.1 is no float32: C holds the nearest one, and so does the interpreter now
        assert published[k] == [ctypes.c_float(0.1).value] * program.items[k].count
    kept = list(published)
    io.pull(published)
    assert all(a is b for a, b in zip(published, kept))  # nothing changed: nothing replaced
    io.items[floats[0]][0] = 2.5  # what a client's write does
    io.pull(published)
    assert published[floats[0]][0] == 2.5 and all(published[k] is kept[k] for k in range(len(kept)) if k != floats[0])
