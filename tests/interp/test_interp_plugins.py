"""Actor plug-ins: the ABI, the cache (reused, keyed by source and compiler),
and clear errors for C code that does not compile."""

from __future__ import annotations

import ctypes
import os

import pytest

from easylab.interp.plugins import PluginCache, PluginError, cache_dir, plugin_source
from interp_testlib import DATA, EXAMPLES, lower, run_interp

BROKEN = """
model broken
import std

actor type Broken() {
    in  x: int16
    out y: int16
    step {{ y = x + ; }}
}

var out: int16
var src: int16
dataflow D {
    b = Broken()
    src -> b.x
    b.y -> out
}
task t period 10 ms { run D }
"""


def test_broken_inline_c_is_one_clear_error(tmp_path, capsys):
    model = tmp_path / "broken.elab"
    model.write_text(BROKEN)
    trace = tmp_path / "t.csv"
    assert run_interp(model, trace, "1s") == 1
    err = capsys.readouterr().err
    assert "actor type 'Broken'" in err
    assert "does not compile" in err
    assert "error: expected expression" in err  # gcc's own message
    assert "Traceback" not in err
    assert err.count("easylab: error:") == 1
    assert not trace.exists()  # nothing ran


def test_cache_is_reused(tmp_path, monkeypatch):
    monkeypatch.setenv("EASYLAB_CACHE", str(tmp_path / "cache"))
    program = lower(EXAMPLES / "pt100_sensor.elab")
    first = PluginCache()
    plugins = first.load_all(program.specs)
    assert first.compiled == len(program.specs) and first.reused == 0
    stamps = {p.path: p.path.stat().st_mtime_ns for p in plugins}
    assert all(path.parent == tmp_path / "cache" for path in stamps)

    second = PluginCache()
    again = second.load_all(program.specs)
    assert second.compiled == 0 and second.reused == len(program.specs)
    assert [p.digest for p in again] == [p.digest for p in plugins]
    assert {p.path: p.path.stat().st_mtime_ns for p in again} == stamps

    # Through the command line too: a second run builds nothing.
    trace = tmp_path / "t.csv"
    assert run_interp(EXAMPLES / "pt100_sensor.elab", trace, "100ms") == 0
    assert {p: p.stat().st_mtime_ns for p in stamps} == stamps


def test_cache_key_follows_source_and_compiler(tmp_path, monkeypatch):
    monkeypatch.setenv("EASYLAB_CACHE", str(tmp_path))
    program = lower(EXAMPLES / "pt100_sensor.elab")
    spec = program.specs[0]
    cache = PluginCache()
    digest = cache.digest(plugin_source(spec))
    assert digest == PluginCache().digest(plugin_source(spec))
    assert cache.digest(plugin_source(spec) + " ") != digest
    other = PluginCache()
    other.__dict__["compiler_identity"] = "gcc (a newer one) 99.0\n"
    assert other.digest(plugin_source(spec)) != digest


def test_damaged_cache_entry_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("EASYLAB_CACHE", str(tmp_path))
    spec = lower(EXAMPLES / "blink.elab").specs[0]
    cache = PluginCache()
    (tmp_path / f"{cache.digest(plugin_source(spec))}.so").write_bytes(b"not a shared library")
    plugin = cache.load(spec)
    assert cache.compiled == 1 and cache.reused == 0
    assert plugin.state_size == 4  # SquareWave: uint16_t count, bool level


def test_cache_location(monkeypatch, tmp_path):
    monkeypatch.setenv("EASYLAB_CACHE", str(tmp_path / "x"))
    assert cache_dir() == tmp_path / "x"
    monkeypatch.delenv("EASYLAB_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "xdg" / "easylab" / "plugins"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cache_dir() == tmp_path / "home" / ".cache" / "easylab" / "plugins"


def test_abi_by_hand():
    """The documented ABI, called directly: Stage(p = 2, c = 3) of cd_to_dat
    (state, a rate-3 input, a rate-2 output) and the std PID (scalars and a
    run-time parameter)."""
    program = lower(EXAMPLES / "cd_to_dat.elab")
    stage = next(s for s in program.specs if s.type_name == "Stage" and s.const_args["c"][1] == 3)
    plugin = PluginCache().load(stage)
    assert plugin.state_size == 4  # uint32_t acc
    state = (ctypes.c_uint64 * 1)()
    x = (ctypes.c_uint32 * 3)(1, 2, 3)
    y = (ctypes.c_uint32 * 2)()
    inputs = (ctypes.c_void_p * 1)(ctypes.addressof(x))
    outputs = (ctypes.c_void_p * 1)(ctypes.addressof(y))
    plugin.start(ctypes.addressof(state))
    plugin.step(ctypes.addressof(state), ctypes.addressof(inputs), ctypes.addressof(outputs), None)
    assert list(y) == [6, 7]
    plugin.step(ctypes.addressof(state), ctypes.addressof(inputs), ctypes.addressof(outputs), None)
    assert list(y) == [12, 13]

    program = lower(EXAMPLES / "line_follower.elab")
    pid = next(s for s in program.specs if s.type_name == "PID")
    assert list(pid.runtime_params) == ["kp"]
    plugin = PluginCache().load(pid)
    state = (ctypes.c_uint64 * 1)()
    setpoint, measured, y, kp = ctypes.c_int16(100), ctypes.c_int16(40), ctypes.c_int16(), ctypes.c_int32(2000)
    inputs = (ctypes.c_void_p * 2)(ctypes.addressof(setpoint), ctypes.addressof(measured))
    outputs = (ctypes.c_void_p * 1)(ctypes.addressof(y))
    params = (ctypes.c_void_p * 1)(ctypes.addressof(kp))
    plugin.step(ctypes.addressof(state), ctypes.addressof(inputs), ctypes.addressof(outputs),
                ctypes.addressof(params))
    assert y.value == 120  # (60 * 2000 + 0) / 1000, within the PID's -255..255


def test_plugin_has_the_firmware_actor_code():
    """One actor C source: the plug-in holds the firmware's block for the
    specialisation (impl file included), and exports only the ABI."""
    program = lower(DATA / "multirate.elab")
    spec = next(s for s in program.specs if s.type_name == "ImplCounter")
    source = plugin_source(spec)
    assert "static int32_t twice(int32_t v)" in source  # the impl file's file-scope code
    assert "base = 1000;" in source and "#define base (el_self->base)" in source
    plugin = PluginCache().load(spec)
    state = (ctypes.c_int32 * 1)()
    plugin.start(ctypes.addressof(state))
    assert state[0] == 1000
    exported = os.popen(f"nm -D --defined-only {plugin.path}").read()
    names = sorted(line.split()[-1] for line in exported.splitlines() if " T " in line)
    assert names == ["el_plugin_abi_version", "el_plugin_start", "el_plugin_state_size", "el_plugin_step",
                     "el_plugin_stop"]


def test_missing_compiler_is_reported(tmp_path, monkeypatch):
    monkeypatch.setenv("EASYLAB_CACHE", str(tmp_path))
    cache = PluginCache(compiler="no-such-cc")
    with pytest.raises(PluginError, match="'no-such-cc' is not installed"):
        cache.load_all(lower(EXAMPLES / "blink.elab").specs)


def test_plugin_source_does_not_depend_on_place():
    """Moving an actor type in its file, or adding specialisations before
    it, keeps its plug-in (and so its state across a live replacement)."""
    program = lower(EXAMPLES / "line_follower.elab")
    for spec in program.specs:
        moved = type(spec)(**{**spec.__dict__, "id": spec.id + 5, "c_name": spec.c_name + "x",
                              "location": spec.location.rsplit(":", 1)[0] + ":999"})
        assert plugin_source(moved) == plugin_source(spec)
