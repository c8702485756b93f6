"""Malformed maps given to the host tools (--map): whatever the file holds,
easylab-debug and easylab-service say in one line what is wrong and exit
non-zero, never with a traceback; the loaders raise only MapError, and a
map they accept can be used (host_tools/map_schema.py)."""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from easylab.host_tools import debug_map, service_map

SETTINGS = settings(max_examples=150, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

DEBUG_MAP = {
    "format": "easylab-debug-map", "version": 1, "model": "m", "title": "t", "program_id": "0x12345678",
    "tick_us": 1000, "interface": {"resource": "uart0", "baud": 115200},
    "items": [{"id": 0, "name": "p", "kind": "param", "type": "uint16", "count": 1,
               "flags": ["read", "write", "range"], "unit": "ms", "range": [10, 5000], "location": "m.elab:3:7"}],
    "charts": [{"id": 0, "name": "C", "task": 0, "location": "m.elab:9:1", "slots": 1,
                "steps": [{"id": 0, "name": "A", "slot": 0, "location": "m.elab:10:5"}],
                "transitions": [{"id": 0, "name": "A -> A", "sources": [0], "targets": [0],
                                 "location": "m.elab:11:5"}]}],
    "actors": [{"id": 0, "name": "D.w", "type": "SquareWave", "dataflow": 0, "task": 0, "location": "m.elab:6:5",
                "states": []}],
    "tasks": [{"id": 0, "name": "main", "period_us": 1000, "offset_us": 0, "deadline_us": 1000,
               "location": "m.elab:12:1"}],
}
SERVICE_MAP = {
    "format": 1, "model": "m", "title": "t", "program_id": "0x12345678",
    "interfaces": {"tcp": {"port": 1502, "unit": 1}},
    "items": [{"id": 0, "name": "p", "kind": "param", "table": "holding", "address": 0, "registers": 1,
               "type": "uint16", "scale": 1, "unit": "ms", "range": [10, 5000], "access": "rw", "persist": False,
               "initial": 500, "location": "m.elab:3"},
              {"id": 1, "name": "f", "kind": "var", "table": "input", "address": 1, "registers": 2,
               "type": "float32", "scale": 1, "unit": None, "range": None, "access": "ro", "persist": False,
               "initial": 0.0, "location": "m.elab:4"}],
}

# The instances found by hand, as file texts.
MALFORMED = {
    "an array": "[]",
    "100,000 nested arrays": "[" * 100_000,
    "a 5,000-digit number": '{"format": ' + "9" * 5000 + "}",
    "not JSON": "{",
    "NaN": '{"format": NaN}',
    "not UTF-8": b"\xff\xfe{}",
}


def _variants(base: dict) -> dict[str, str]:
    """Maps broken in one place each: a one-element range, a name that is an
    object, an address above 65535, an item that is a number."""
    out = {}
    for label, change in [
        ("a one-element range", lambda m: m["items"][0].__setitem__("range", [1])),
        ("a name that is an object", lambda m: m["items"][0].__setitem__("name", {"a": 1})),
        # an address above 65535 (a service map), a count of 70000 (a debug map)
        ("a number above 65535", lambda m: m["items"][0].__setitem__("address" if "table" in m["items"][0]
                                                                      else "count", 70000)),
        ("an id above 65535", lambda m: m["items"][0].__setitem__("id", 70000)),
        ("an item that is a number", lambda m: m["items"].__setitem__(0, 3)),
        ("items that are an object", lambda m: m.__setitem__("items", {})),
        ("no items", lambda m: m.pop("items")),
        ("a range bound beyond float32", lambda m: m["items"][0].__setitem__("range", [0, 1e39])),
    ]:
        broken = copy.deepcopy(base)
        change(broken)
        out[label] = json.dumps(broken)
    return out


def _write(tmp_path: Path, text) -> Path:
    path = tmp_path / "map.json"
    path.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8"))
    return path


def _tool(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", "import sys; from easylab.host_tools.%s import main; "
                           "sys.exit(main(sys.argv[1:]))" % args[0], *args[1:]], capture_output=True, text=True,
                          env=dict(os.environ), timeout=60, stdin=subprocess.DEVNULL)


CASES = ([(label, text, "debug") for label, text in {**MALFORMED, **_variants(DEBUG_MAP)}.items()]
         + [(label, text, "service") for label, text in {**MALFORMED, **_variants(SERVICE_MAP)}.items()])


@pytest.mark.parametrize("label, text, tool", CASES, ids=[f"{c[2]}-{c[0]}" for c in CASES])
def test_a_malformed_map_is_one_line_and_a_non_zero_status(tmp_path, label, text, tool):
    path = _write(tmp_path, text)
    if tool == "debug":
        proc = _tool("debug_console", "--map", str(path), str(tmp_path / "no-link"), "-c", "vars")
    else:
        proc = _tool("service_cli", "--map", str(path), "--tcp", "127.0.0.1:1", "read", "p")
    assert proc.returncode != 0
    assert "Traceback" not in proc.stderr, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and str(path) in lines[0] and "not a " in lines[0], proc.stderr


def test_the_good_maps_load():
    """The two maps the malformed ones are made from are valid."""
    assert isinstance(json.loads(json.dumps(DEBUG_MAP)), dict)


def _load_and_use(path: Path, which: str) -> None:
    """Load a map and use what the tools use of it; only MapError may come out."""
    if which == "debug":
        try:
            m = debug_map.DebugMap.load(path)
        except debug_map.MapError as err:
            assert "\n" not in str(err)
            return
        m.points()
        m.glob(None)
        for item in m.items:
            m.item(item.name)
    else:
        try:
            m = service_map.load_map(path)
        except service_map.MapError as err:
            assert "\n" not in str(err)
            return
        service_map.read_groups(m.items)
        m.params()
        for item in m.items:
            item.describe_range()
            item.to_registers(item.from_registers([0, 0]))


def test_the_base_maps_are_accepted(tmp_path):
    for which, base in (("debug", DEBUG_MAP), ("service", SERVICE_MAP)):
        path = _write(tmp_path, json.dumps(base))
        loaded = debug_map.DebugMap.load(path) if which == "debug" else service_map.load_map(path)
        assert loaded.items


JSON = st.recursive(
    st.none() | st.booleans() | st.integers(-2 ** 70, 2 ** 70) | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
    max_leaves=20)


@SETTINGS
@given(st.sampled_from(["debug", "service"]), JSON)
def test_arbitrary_json_never_raises_anything_but_a_map_error(tmp_path, which, value):
    _load_and_use(_write(tmp_path, json.dumps(value)), which)


def _paths(value, prefix=()):
    yield prefix
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _paths(v, prefix + (i,))


@SETTINGS
@given(st.sampled_from(["debug", "service"]), st.data(), JSON)
def test_a_good_map_changed_in_one_place_never_raises_anything_but_a_map_error(tmp_path, which, data, value):
    doc = copy.deepcopy(DEBUG_MAP if which == "debug" else SERVICE_MAP)
    where = data.draw(st.sampled_from(list(_paths(doc))[1:]))
    target = doc
    for key in where[:-1]:
        target = target[key]
    if data.draw(st.booleans()):
        target[where[-1]] = value
    else:
        del target[where[-1]]
    _load_and_use(_write(tmp_path, json.dumps(doc)), which)
