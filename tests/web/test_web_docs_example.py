"""docs/service.md's web panel example, run as written: its commands (build
the shipped examples/pt100_tcp/pt100_sensor_tcp.elab, start the firmware
with --modbus-tcp 1502, start the panel) from a folder laid out as the
repository's top, the panel's first line as the document shows it, and
the page's API serving the device's values. Also what the document says
the firmware of a model without Modbus TCP does with --modbus-tcp."""

from __future__ import annotations

import os
import re
import shlex
import signal
import subprocess
import sys
from pathlib import Path

from weblib import ROOT, http, wait_for

DOC = ROOT / "docs" / "service.md"


def doc_example() -> tuple[list[str], str]:
    """The example's commands (without `$ `) and the output line after them."""
    text = DOC.read_text()
    block = re.search(r"from the repository's top folder:\n\n```\n(.*?)```", text, re.S)
    assert block, "docs/service.md: the panel example is missing"
    lines = block.group(1).splitlines()
    commands = [line[2:] for line in lines if line.startswith("$ ")]
    outputs = [line for line in lines if not line.startswith("$ ")]
    assert len(commands) == 3 and len(outputs) == 1, lines
    return commands, outputs[0]


def tool_env() -> dict:
    """The installed commands (easylab, easylab-service) first on PATH."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    return env


def test_the_tcp_example_works_as_written(tmp_path):
    commands, expected = doc_example()
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    env = tool_env()
    build, firmware, panel = commands
    proc = subprocess.run(shlex.split(build), cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert firmware.endswith(" &")
    started = []
    try:
        fw = subprocess.Popen(shlex.split(firmware[:-2]), cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True)
        started.append(fw)
        web = subprocess.Popen(shlex.split(panel), cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
        started.append(web)
        first = web.stdout.readline().rstrip("\n")
        assert first == expected, (first, web.poll() is not None and web.stderr.read())
        url = re.search(r"(http://\S+)", first).group(1)
        doc = wait_for(lambda: (lambda d: d if d["link"]["state"] == "connected" and d["samples"] else None)(
            http("GET", url + "api/samples?after=-1").json()), timeout=15, what="the panel to sample the device")
        names = [it["name"] for it in http("GET", url + "api/map").json()["items"]]
        temperature = doc["samples"][-1]["v"][names.index("temperature")]
        assert isinstance(temperature, int) and -2000 <= temperature <= 8500  # tenths of a degC
        assert fw.poll() is None
    finally:
        for proc in reversed(started):
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
                proc.wait(timeout=15)


def test_a_firmware_without_modbus_tcp_refuses_the_option_as_the_document_says(tmp_path):
    out = tmp_path / "pt100_sensor"
    proc = subprocess.run(["easylab", "build", str(ROOT / "examples" / "pt100_sensor.elab"), "--board", "host",
                           "-o", str(out)], env=tool_env(), capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    run = subprocess.run([str(out / "pt100_sensor"), "--modbus-tcp", "1502"], capture_output=True, text=True,
                         timeout=30)
    assert run.returncode == 2 and run.stdout == ""
    message = run.stderr.strip()
    assert message == ("pt100_sensor: --modbus-tcp: model pt100_sensor has no Modbus TCP interface "
                       "(declare one: `modbus tcp port 1502`)")
    text = " ".join(DOC.read_text().split())
    assert "exits with status 2 (``" + message + "``)" in text
