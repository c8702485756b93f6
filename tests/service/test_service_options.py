"""Serving a Modbus interface the model does not declare is a command-line
error (exit status 2, naming the missing interface), on the host board and
in local execution, as --debug is for a model without a debug interface:
a program that accepted the connections and closed them could not be told
from a network fault."""

from __future__ import annotations

import subprocess

import pytest

from firmware_builds import ROOT, cli

BLINK = ROOT / "examples" / "blink.elab"


@pytest.mark.parametrize("option, value, missing", [
    ("--modbus-tcp", "15031", "has no Modbus TCP interface (declare one: `modbus tcp port 15031`)"),
    ("--modbus-rtu", "pty:{tmp}/mb", "has no Modbus RTU interface"),
])
def test_a_modbus_interface_the_model_lacks_is_a_command_line_error(build_cache, tmp_path, option, value, missing):
    exe = build_cache.example("host", "blink").executable
    arg = value.format(tmp=tmp_path)
    trace = tmp_path / "t.csv"
    proc = subprocess.run([str(exe), option, arg, "--fast", "--duration", "100ms", "--trace", str(trace)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2, proc.stderr
    assert f"blink: {option}: model blink {missing}" in proc.stderr
    assert not trace.exists() and not (tmp_path / "mb").exists()
    proc = cli("run", BLINK, option, arg, "--fast", "--duration", "100ms", "--trace", trace)
    assert proc.returncode == 2, proc.stderr
    assert f"{option}: model blink {missing}" in proc.stderr
    assert not trace.exists()
