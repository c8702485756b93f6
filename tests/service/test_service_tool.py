"""`easylab-service` (host_tools/service_cli.py) against running host
firmware (and, for reads, writes, backup and restore, against local
execution: `easylab run`): list, read, write in the model's units, monitor with a CSV file,
backup and restore; timeouts, exceptions, unknown names and a wrong device
give one clear line and an exit status, never a traceback."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
import tomllib

import pytest

from svc_testlib import ROOT


@pytest.fixture
def svc(tool_env, svc_all, firmware):
    fw = firmware(svc_all.exe)

    def run(*args, map_=None, expect=0):
        cmd = [sys.executable, "-m", "easylab.host_tools.service_cli", "--map", str(map_ or svc_all.map), *args]
        proc = subprocess.run(cmd, capture_output=True, text=True, env=tool_env, timeout=60)
        assert "Traceback" not in proc.stderr, proc.stderr
        assert proc.returncode == expect, (proc.returncode, proc.stdout, proc.stderr)
        return proc
    run.fw = fw
    run.tcp = ["--tcp", f"127.0.0.1:{fw.port}"]
    run.rtu = ["--rtu", str(fw.rtu), "--parity", "N"]
    return run


def test_console_script_is_declared():
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts["easylab-service"] == "easylab.host_tools.service_cli:main"


def test_list_needs_no_device(svc):
    out = svc("list").stdout
    assert "model service_all" in out
    assert any(line.split()[:4] == ["p_i32", "holding", "4..5", "int32"] for line in out.splitlines())
    assert any(line.split()[:3] == ["p_far", "holding", "100"] for line in out.splitlines())


@pytest.mark.parametrize("board", ["host", "interp"], indirect=True)
def test_read_and_write_in_model_units(board, svc):
    out = svc(*svc.tcp, "read", "p_i16", "p_f32", "p_time", "p_flag", "m_u32").stdout
    assert out.splitlines() == ["p_i16 = -300 0.1 degC", "p_f32 = 1.5 bar", "p_time = 2000 ms", "p_flag = 0",
                                "m_u32 = 3000000000"]
    assert svc(*svc.tcp, "write", "p_time", "5s").stdout == "p_time = 5000 ms\n"
    assert svc(*svc.tcp, "write", "p_f32", "-9.5").stdout == "p_f32 = -9.5 bar\n"
    assert svc(*svc.rtu, "write", "--", "p_i8", "-0x10").stdout == "p_i8 = -16 x\n"
    assert svc(*svc.rtu, "write", "cmd", "on").stdout == "cmd = 1\n"
    assert svc(*svc.rtu, "read", "p_time", "p_i8").stdout == "p_time = 5000 ms\np_i8 = -16 x\n"


def test_errors_are_one_line(svc, builds):
    err = svc(*svc.tcp, "write", "p_i8", "101", expect=1).stderr
    assert err == ("easylab-service: error: 101 is outside the range of 'p_i8' (-100..100 x): the device refused "
                   "it (exception 03), nothing changed\n")
    err = svc(*svc.tcp, "write", "m_i8", "1", expect=2).stderr
    assert err == "easylab-service: error: 'm_i8' is read-only (service ro)\n"
    err = svc(*svc.tcp, "read", "p_i9", expect=2).stderr
    assert "'p_i9' is not a service item of model 'service_all' (did you mean 'p_i8'?)" in err
    err = svc(*svc.tcp, "write", "p_u8", "300", expect=2).stderr
    assert "300 does not fit 'p_u8' (uint8: 0..255)" in err
    err = svc(*svc.tcp, "write", "p_f32", "lots", expect=2).stderr
    assert "'lots' is not a number for 'p_f32'" in err
    err = svc("read", "p_i8", expect=2).stderr
    assert "give the device: --tcp HOST:PORT or --rtu PORT" in err
    err = svc("--tcp", "127.0.0.1:1", "read", "p_i8", expect=1).stderr
    assert "cannot connect to 127.0.0.1:1" in err
    # A unit nobody answers: a timeout.
    err = svc("--rtu", str(svc.fw.rtu), "--parity", "N", "--unit", "9", "--timeout", "0.3", "read", "p_i8",
              expect=1).stderr
    assert "no reply from" in err and "within 0.3 s" in err
    # The map of another model: a wrong device.
    other = builds("pt100_sensor").map
    err = svc(*svc.tcp, "read", "cal_gain", map_=other, expect=1).stderr
    assert "wrong device" in err and "runs model 'service_all'" in err and "model 'pt100_sensor'" in err
    err = svc(*svc.tcp, "read", "p_i8", map_=svc.fw.exe.parent / "nothing.json", expect=2).stderr
    assert "no such map file" in err
    err = svc(*svc.rtu[:2], "--parity", "E", "read", "p_i8", expect=1).stderr
    assert "use --parity N" in err


def test_monitor_writes_a_table_and_a_csv(svc, tmp_path):
    out_csv = tmp_path / "m.csv"
    out = svc(*svc.tcp, "monitor", "p_i16", "m_f32", "--every", "50ms", "--count", "4", "--csv", str(out_csv)).stdout
    lines = out.splitlines()
    assert lines[0].split() == ["time_s", "p_i16", "[0.1", "degC]", "m_f32", "[bar]"]
    assert len(lines) == 5
    rows = list(csv.reader(out_csv.open()))
    assert rows[0] == ["time_s", "p_i16", "m_f32"]
    assert len(rows) == 5 and all(r[1:] == ["-300", "1.5"] for r in rows[1:])
    times = [float(r[0]) for r in rows[1:]]
    assert times == sorted(times) and times[-1] >= 0.14


@pytest.mark.parametrize("board", ["host", "interp"], indirect=True)
def test_backup_and_restore(board, svc, tmp_path):
    backup = tmp_path / "params.json"
    assert svc(*svc.tcp, "backup", str(backup)).stdout.startswith("backed up 10 params")
    saved = json.loads(backup.read_text())
    assert saved["params"]["p_u32"] == 3000000000 and saved["params"]["p_f32"] == 1.5
    assert "cmd" not in saved["params"]                     # vars are not params
    svc(*svc.tcp, "write", "p_u32", "1")
    svc(*svc.tcp, "write", "p_f32", "2.25")
    svc(*svc.tcp, "write", "p_flag", "1")
    assert "restored 10 of 10 params" in svc(*svc.rtu, "restore", str(backup)).stdout
    assert svc(*svc.tcp, "read", "p_u32", "p_f32", "p_flag").stdout == "p_u32 = 3000000000\np_f32 = 1.5 bar\n" \
                                                                      "p_flag = 0\n"
    # A value the device refuses is reported, the others are restored.
    saved["params"]["p_i16"] = 5000
    backup.write_text(json.dumps(saved))
    proc = svc(*svc.tcp, "restore", str(backup), expect=1)
    assert "p_i16: 5000 is outside the range of 'p_i16'" in proc.stderr
    assert "restored 9 of 10 params" in proc.stdout
    saved["model"] = "other"
    backup.write_text(json.dumps(saved))
    assert "is a backup of model 'other'" in svc(*svc.tcp, "restore", str(backup), expect=2).stderr
