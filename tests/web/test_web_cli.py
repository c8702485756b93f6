"""`easylab-service web` on the command line: its help, one clear line for
every mistake a user can make (no traceback), a device that is not there
yet or is not the map's, and a clean stop."""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys

from svc_testlib import free_port
from weblib import Pt100Devices, wait_for

TOOL = [sys.executable, "-m", "easylab.host_tools.service_cli"]


def run(*args: str, expect: int) -> subprocess.CompletedProcess:
    proc = subprocess.run([*TOOL, *args], capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert "Traceback" not in proc.stderr, proc.stderr
    assert proc.returncode == expect, (proc.returncode, proc.stdout, proc.stderr)
    return proc


def test_help_describes_the_command_and_its_safety():
    assert "web" in run("--help", expect=0).stdout
    out = run("web", "--help", expect=0).stdout
    for text in ("--listen ADDR:PORT", "--token TOKEN", "--every PERIOD", "default 127.0.0.1:8080",
                 "a token is\nrequired", "CSRF header", "reconnects by itself"):
        assert text in out, text


def test_mistakes_are_one_line(pt100_tcp, tmp_path):
    smap = str(pt100_tcp.map)
    cases = [
        (["--map", str(tmp_path / "none.json"), "--tcp", "127.0.0.1:1502", "web"], "no such map file"),
        (["--map", smap, "web"], "give the device: --tcp HOST:PORT or --rtu PORT"),
        (["--map", smap, "--tcp", "127.0.0.1:1502", "web", "--listen", "8080"], "--listen 8080: give ADDR:PORT"),
        (["--map", smap, "--tcp", "127.0.0.1:1502", "web", "--listen", "panel.example:80"],
         "panel.example is not an IP address"),
        (["--map", smap, "--tcp", "127.0.0.1:1502", "web", "--listen", "127.0.0.1:70000"], "port 70000 is not"),
        (["--map", smap, "--tcp", "127.0.0.1:1502", "web", "--token", "short"], "--token: give 8 to 128"),
        (["--map", smap, "--tcp", "127.0.0.1:1502", "web", "--every", "fast"], "--every fast: give a period"),
    ]
    bad_map = tmp_path / "bad.json"
    bad_map.write_text("{not json")
    cases.append((["--map", str(bad_map), "--tcp", "127.0.0.1:1502", "web"], "not a service map"))
    for args, message in cases:
        err = run(*args, expect=2).stderr
        assert err.count("\n") == 1 and err.startswith("easylab-service: error: ") and message in err, (args, err)


def test_a_port_in_use_is_one_line(pt100_tcp):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        err = run("--map", str(pt100_tcp.map), "--tcp", "127.0.0.1:1502", "web", "--listen", f"127.0.0.1:{port}",
                  expect=2).stderr
    assert err == f"easylab-service: error: cannot listen on 127.0.0.1:{port}: the port is in use\n"


def test_a_device_that_comes_later_is_picked_up(pt100_tcp, stimulus, tmp_path, panel, browser):
    port = free_port()
    p = panel(pt100_tcp.map, "--tcp", f"127.0.0.1:{port}")
    link = wait_for(lambda: (lambda link: "cannot connect" in link["message"] and link)(p.link()),
                    what="the first attempt")
    assert link["state"] == "connecting" and link["connects"] == 0
    assert link["message"] == (f"cannot connect to 127.0.0.1:{port} (nothing listens there, or it refused); "
                               "trying again")
    wait_for(lambda: any(f"cannot connect to 127.0.0.1:{port}" in line for line in p.err), what="the log line")
    assert p.api("POST", "/api/write", {"name": "cal_offset", "value": "1"}).status == 503
    browser.get(p.url)
    wait_for(lambda: (browser.text("#banner") or "").startswith(f"Waiting for the device at 127.0.0.1:{port}"),
             what="the page's waiting message")
    devices = Pt100Devices(pt100_tcp.exe, stimulus, tmp_path)
    try:
        devices.start(port=port)
        wait_for(lambda: browser.text("#link-state") == "connected", timeout=15, what="the page to connect")
        assert any(line.startswith(f"easylab-service: connected to 127.0.0.1:{port}") for line in p.err)
    finally:
        devices.stop_all()


def test_a_device_that_runs_another_program_is_refused(pt100_tcp, stimulus, tmp_path, panel):
    devices = Pt100Devices(pt100_tcp.exe, stimulus, tmp_path)
    fw = devices.start()
    try:
        other = json.loads(pt100_tcp.map.read_text())
        other["program_id"] = "0x12345678"
        other_map = tmp_path / "other_map.json"
        other_map.write_text(json.dumps(other))
        p = panel(other_map, "--tcp", f"127.0.0.1:{fw.port}")
        wait_for(lambda: "wrong device" in p.link()["message"], what="the refusal")
        assert p.link()["state"] == "connecting" and p.api("GET", "/api/samples").json()["samples"] == []
    finally:
        devices.stop_all()


def test_sigint_stops_the_panel_cleanly(pt100_tcp, panel):
    p = panel(pt100_tcp.map, "--tcp", f"127.0.0.1:{free_port()}")
    p.proc.send_signal(signal.SIGINT)
    assert p.proc.wait(timeout=15) == 0
    assert "Traceback" not in "".join(p.err)
