"""easylab-debug, non-interactive: -c, --script, --json, and its one-line
failures (wrong map, no answer, a port that goes away)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

from debug_testlib import board, builds, env_with_tools, firmware  # noqa: F401 (fixtures)

ENV = env_with_tools()


def console(*args, timeout=30):
    proc = subprocess.run([sys.executable, "-m", "easylab.host_tools.debug_console", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, env=ENV)
    return proc.returncode, proc.stdout, proc.stderr


@pytest.mark.parametrize("board", ["host", "interp"], indirect=True)  # the firmware, and `easylab run`
def test_commands_from_c_and_read_output(board, builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"])
    status, out, err = console("--map", fw.map_path, fw.link, "-c",
                               "read target timeout start_cmd; write start_cmd 1; break at Cylinder.Extending; "
                               "breakpoints; run; wait 5s; stack; step actor; delete 0; info; counters; vars *pid*; "
                               "vars PositionControl.*")
    assert status == 0, err
    lines = out.splitlines()
    assert lines[:3] == ["target = 900", "timeout = 2000", "start_cmd = false"]
    assert "start_cmd := true (applied)" in lines
    assert "breakpoint 0 at step Cylinder.Extending" in lines
    assert any(line.startswith("halted (breakpoint) at breakpoint 0 at step Cylinder.Extending") for line in lines)
    assert "chart       Cylinder: Extending" in lines
    assert any(line.startswith("halted (step) at actor:PositionControl.") for line in lines)
    assert any("PositionControl.pid.integral" in line and "state" in line for line in lines)
    assert err == ""


@pytest.mark.parametrize("board", ["host", "interp"], indirect=True)
def test_json_output_and_script(board, builds, firmware, tmp_path):
    fw = firmware(builds["pneumatic_cylinder"])
    script = tmp_path / "s.dbg"
    script.write_text("# a script\nread kp ki\ntx begin\nwrite kp 500\nwrite ki 30\nread kp\ntx commit\n"
                      "watch kp --count 2 --every 10ms\nstack\n")
    status, out, err = console("--map", fw.map_path, fw.link, "--script", script, "--json")
    assert status == 0, err
    objs = [json.loads(line) for line in out.splitlines()]
    assert objs[0] == {"name": "kp", "value": 400} and objs[1] == {"name": "ki", "value": 20}
    assert {"name": "kp", "value": 500} in objs  # the transaction's read, at the commit
    watch = [o for o in objs if "values" in o]
    assert len(watch) == 2 and watch[0]["values"] == {"kp": 500}
    assert objs[-1]["charts"] == [{"chart": "Cylinder", "active": []}]


def test_errors_in_scripts_are_one_line_with_status_1(builds, firmware, tmp_path):
    fw = firmware(builds["pneumatic_cylinder"])
    for cmd, message in [("write valve.duty 3", "valve.duty is read-only"),
                         ("write target 5000", "outside its range 0..1023"),
                         ("write start_cmd 7", "is a bool"),
                         ("read nosuch", "no item 'nosuch'"),
                         ("break at Nowhere.Step", "no step, transition, actor, chart or task"),
                         ("frobnicate", "unknown command")]:
        status, out, err = console("--map", fw.map_path, fw.link, "-c", cmd)
        assert status == 1 and message in err and err.count("\n") == 1, (cmd, err)
        assert "Traceback" not in err


def test_refuses_a_firmware_that_does_not_match_the_map(builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"])
    other = builds["blink"].parent / "debug_map.json"
    status, out, err = console("--map", other, fw.link, "-c", "info")
    assert status == 2 and out == ""
    assert f"runs program 0x{fw.map.program_id:08x}" in err and "debug map of model blink" in err
    assert "use the debug_map.json" in err and err.count("\n") == 1


def test_no_answer_and_missing_port_are_one_line(tmp_path):
    master, slave = os.openpty()  # a port where nothing answers
    try:
        status, out, err = console(os.ttyname(slave), "--timeout", "0.3", "-c", "info")
    finally:
        os.close(master)
        os.close(slave)
    assert status == 1 and "no answer from" in err and "is the firmware running" in err
    assert err.count("\n") == 1
    status, out, err = console(tmp_path / "nothing", "-c", "info")
    assert status == 1 and err == f"easylab-debug: error: cannot open {tmp_path / 'nothing'}: no such device or file\n"


def test_a_port_that_goes_away_is_one_line(builds, firmware):
    fw = firmware(builds["pneumatic_cylinder"], halt=False, fast=False)
    proc = subprocess.Popen([sys.executable, "-m", "easylab.host_tools.debug_console", "--map", str(fw.map_path),
                             str(fw.link), "-c", "watch cycles --count 1000 --every 20ms"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
    time.sleep(1.0)
    fw.proc.kill()  # unplugged
    out, err = proc.communicate(timeout=20)
    assert proc.returncode == 1
    assert err.startswith("easylab-debug: error: ") and err.count("\n") == 1 and "Traceback" not in err


def test_load_replaces_the_model_in_local_execution(tmp_path):
    """`load FILE` sends a model to `easylab run --debug`: a broken one is
    refused with the checker's message (status 1, the program runs on), a
    good one replaces the program, and the console reloads the map that
    --maps rewrote; a firmware cannot load and says so."""
    from debug_testlib import EXAMPLES, Firmware, InterpFirmware, built

    model = tmp_path / "blink.elab"
    model.write_text((EXAMPLES / "blink.elab").read_text())
    faster = tmp_path / "faster.elab"
    faster.write_text(model.read_text().replace("= 500 range", "= 20 range"))
    broken = tmp_path / "broken.elab"
    broken.write_text(model.read_text().replace("wave.y -> led.level", "wave.y -> nowhere"))
    fw = InterpFirmware(model, tmp_path, halt=False, fast=False)
    try:
        status, out, err = console("--map", fw.map_path, fw.link, "-c", f"load {broken}")
        assert status == 1 and "refused, the program runs on" in err and "'nowhere'" in err, err
        status, out, err = console("--map", fw.map_path, fw.link, "-c", f"read half_period; load {faster}; "
                                   "read half_period; info")
        assert status == 0, err
        lines = out.splitlines()
        assert lines[0] == "half_period = 500" and lines[1].startswith("replaced: program 0x")
        assert lines[2] == "half_period = 20"
        new_id = lines[1].split()[2]
        assert any(line.startswith("firmware") and f"program {new_id}" in line for line in lines)
        assert json.loads(fw.map_path.read_text())["program_id"] == new_id
    finally:
        fw.stop()
    host = Firmware(built("blink"), tmp_path, halt=False)
    try:
        status, out, err = console("--map", host.map_path, host.link, "-c", f"load {faster}")
        assert status == 1 and "cannot replace its model" in err, err
    finally:
        host.stop()
