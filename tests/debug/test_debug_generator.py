"""What the generator writes for the debug interface, and what a release
build (or a model without a debug interface) leaves out."""

from __future__ import annotations

import json
import shutil
import subprocess

import pytest

from debug_testlib import EXAMPLES, MODELS, build
from easylab.board.registry import load_board
from easylab.codegen import render as cgen
from easylab.core.paths import templates_dir
from easylab.pipeline import lower_file


def render(model, release=False):
    program, result = lower_file(model)
    assert program is not None, result.report()
    return program, cgen.render(program, load_board("host"), templates_dir(), release)


def test_the_map_names_every_id_and_the_output_is_deterministic():
    program, files = render(EXAMPLES / "pneumatic_cylinder.elab")
    assert render(EXAMPLES / "pneumatic_cylinder.elab")[1] == files
    m = json.loads(files["debug_map.json"])
    assert m["program_id"] == f"0x{program.program_id:08x}" and m["model"] == "pneumatic_cylinder"
    assert [i["id"] for i in m["items"]] == list(range(len(m["items"])))
    by_name = {i["name"]: i for i in m["items"]}
    target = dict(by_name["target"])
    assert target.pop("location").endswith("pneumatic_cylinder.elab:13")
    assert target == {"id": 0, "name": "target", "kind": "param", "type": "int16", "count": 1,
                      "flags": ["read", "write", "range"], "unit": None, "range": [0, 1023]}
    assert by_name["valve.duty"]["flags"] == ["read"]  # a device `in` datum is read-only
    assert by_name["PositionControl.pid.integral"]["kind"] == "state"
    assert [s["name"] for s in m["charts"][0]["steps"]] == ["Retracted", "Extending", "Extended", "Retracting",
                                                            "Fault"]
    assert m["charts"][0]["transitions"][0]["name"] == "Retracted -> Extending"
    assert [a["name"] for a in m["actors"]] == ["PositionControl.pid", "PositionControl.sp", "PositionControl.pos",
                                                 "Vent.zero"]
    assert [t["name"] for t in m["tasks"]] == ["control", "lamp"]
    assert "EL_DEBUG_PROBE(EL_DBG_P_TRANSITION, 0u, 0u);" in files["model.c"]
    assert "#define EL_DEBUG_SERVER 1" in files["el_debug_config.h"]


def test_release_and_models_without_a_debug_interface_get_none(tmp_path):
    _, files = render(EXAMPLES / "pneumatic_cylinder.elab", release=True)
    assert not [f for f in files if f.startswith(("debug", "el_debug"))]
    assert "EL_DEBUG" not in files["model.c"] and "el_debug" not in files["model.c"]
    text = (MODELS / "tx16.elab").read_text().replace("debug on uart0 baud 115200", "")
    model = tmp_path / "nodebug.elab"
    model.write_text(text.replace("model tx16", "model nodebug"))
    _, files = render(model)
    assert "debug_tables.c" not in files and "debug_map.json" not in files
    assert "#define EL_DEBUG_SERVER 0" in files["el_debug_config.h"]
    assert "EL_DEBUG_PROBE" not in files["model.c"]
    exe = build(model, tmp_path / "nodebug")
    proc = subprocess.run([str(exe), "--debug", f"pty:{tmp_path / 'x'}"], capture_output=True, text=True)
    assert proc.returncode == 2 and "has no debug interface" in proc.stderr


@pytest.mark.skipif(shutil.which("nm") is None, reason="nm is not installed")
def test_a_release_build_has_no_debug_code_and_no_debug_interface(tmp_path):
    exe = build(EXAMPLES / "pneumatic_cylinder.elab", tmp_path / "rel", release=True)
    symbols = subprocess.run(["nm", str(exe)], capture_output=True, text=True, check=True).stdout
    assert "el_debug" not in symbols and "el_dbg" not in symbols and "el_cobs" not in symbols
    assert not (tmp_path / "rel" / "debug_map.json").exists()
    proc = subprocess.run([str(exe), "--debug", f"pty:{tmp_path / 'link'}", "--fast", "--duration", "10ms"],
                          capture_output=True, text=True)
    assert proc.returncode == 2 and "release build" in proc.stderr
    assert not (tmp_path / "link").exists()  # nothing to send debug frames to
    debug = build(EXAMPLES / "pneumatic_cylinder.elab", tmp_path / "dbg")
    symbols = subprocess.run(["nm", str(debug)], capture_output=True, text=True, check=True).stdout
    assert "el_debug_poll" in symbols


@pytest.mark.parametrize("cc", ["clang", "avr-gcc"])
def test_the_server_compiles_warning_free(cc, tmp_path):
    if shutil.which(cc) is None:
        pytest.skip(f"{cc} is not installed")
    from debug_testlib import ROOT
    program, files = render(EXAMPLES / "line_follower.elab")
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    flags = ["-std=c99", "-Os", "-Wall", "-Wextra", "-Werror", "-pedantic", "-DEL_DEBUG=1",
             f"-I{ROOT / 'runtime_c'}", f"-I{tmp_path}"]
    if cc == "avr-gcc":
        flags.append("-mmcu=atmega2560")
    else:
        flags += ["-Wconversion", "-Wshadow"]
    for src in [ROOT / "runtime_c" / "el_debug.c", ROOT / "runtime_c" / "el_debug_cobs.c", tmp_path / "debug_tables.c"]:
        proc = subprocess.run([cc, *flags, "-c", str(src), "-o", str(tmp_path / "x.o")], capture_output=True,
                              text=True)
        assert proc.returncode == 0, proc.stderr


def test_the_server_is_compiled_for_what_the_model_has():
    """el_debug_config.h switches off the server's code for what a model
    lacks (runtime_c/el_debug.c): blink has no charts, no item of several
    elements and ranges on unsigned items only; pneumatic_cylinder has a
    chart and a signed range, pt100_sensor items of several elements;
    the fuzz target's tables (no config) keep everything. Actor firings
    call the probe with the instance's id, in debug builds only."""
    _, blink = render(EXAMPLES / "blink.elab")
    config = blink["el_debug_config.h"]
    for switch in ("HAS_CHARTS 0", "HAS_ARRAYS 0", "RANGES_UNSIGNED 1", "RANGES_SIGNED 0", "RANGES_FLOAT 0"):
        assert f"#define EL_DBG_{switch}\n" in config, config
    assert "EL_DEBUG_PROBE_ACTOR(0u);" in blink["model.c"]
    _, cylinder = render(EXAMPLES / "pneumatic_cylinder.elab")
    config = cylinder["el_debug_config.h"]
    for switch in ("HAS_CHARTS 1", "RANGES_SIGNED 1", "RANGES_FLOAT 0"):
        assert f"#define EL_DBG_{switch}\n" in config, config
    assert "#define EL_DBG_HAS_ARRAYS 1\n" in render(EXAMPLES / "pt100_sensor.elab")[1]["el_debug_config.h"]
    _, release = render(EXAMPLES / "blink.elab", release=True)
    assert "PROBE" not in release["model.c"]
