"""Conformance with Debian's mbpoll (libmodbus): every kind of item of the
examples with `service` items (pt100_sensor, pneumatic_cylinder) over RTU
on the host board's pty, and of tests/service/data/service_all.elab over
TCP and RTU; exceptions for one past the map's end and for values out of
range. mbpoll's -0 gives PDU addresses (the map's), -B big-endian words."""

from __future__ import annotations

import json
import re
import subprocess
import time

import pytest

from svc_testlib import on_boards, tool_available

pytestmark = pytest.mark.skipif(not tool_available("mbpoll"), reason="mbpoll is not installed (Debian: mbpoll)")


def mbpoll(link_args: list[str], *args: str, values: list[str] | None = None) -> tuple[dict[int, str], str]:
    cmd = ["mbpoll", *link_args, "-0", "-1", "-o", "2", *args]
    if values is not None:
        cmd += ["--", *values]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=30)
    out = {int(m.group(1)): m.group(2).strip() for m in re.finditer(r"^\[(\d+)\]:\s+(.*)$", proc.stdout, re.M)}
    return out, proc.stdout + proc.stderr


def signed(cell: str) -> int:
    """mbpoll shows a 16-bit register as `65531 (-5)`."""
    m = re.fullmatch(r"(-?\d+)(?: \((-?\d+)\))?", cell)
    return int(m.group(2) or m.group(1))


def rtu_args(fw, unit: int, baud: int) -> list[str]:
    # A pty refuses even parity: the clients use 8N1 whatever the model says.
    return ["-m", "rtu", "-a", str(unit), "-b", str(baud), "-P", "none", str(fw.rtu)]


def _split(link_args):
    """mbpoll wants the device last, after the options."""
    return link_args[:-1], link_args[-1]


def run(link_args, *args, values=None):
    opts, dev = _split(link_args)
    cmd_args = [*args, dev]
    return mbpoll(opts, *cmd_args, values=values)


@pytest.fixture(params=["tcp", "rtu"])
def link(request, svc_all, firmware):
    fw = firmware(svc_all.exe)
    if request.param == "tcp":
        return ["-m", "tcp", "-p", str(fw.port), "127.0.0.1"]
    return rtu_args(fw, 3, 115200)


@on_boards
def test_service_all_every_kind(link):
    out, text = run(link, "-t", "4", "-r", "0", "-c", "4")
    assert signed(out[0]) == -5 and out[1] == "7" and signed(out[2]) == -300 and out[3].startswith("40000")
    out, text = run(link, "-t", "4:int", "-B", "-r", "4")
    assert out[4] == "-100000", text
    out, text = run(link, "-t", "4:float", "-B", "-r", "8")
    assert out[8] == "1.5", text
    out, text = run(link, "-t", "4:int", "-B", "-r", "10")
    assert out[10] == "2000", text                                   # time, ms
    out, text = run(link, "-t", "4", "-r", "100")
    assert out[100] == "7", text
    # Writes of every kind, read back.
    assert "Written 1 references" in run(link, "-t", "4", "-r", "0", values=[str(65536 - 99)])[1]
    assert "Written 1 references" in run(link, "-t", "4:int", "-B", "-r", "4", values=["-1999999"])[1]
    assert "Written 1 references" in run(link, "-t", "4:float", "-B", "-r", "8", values=["-2.5"])[1]
    assert "Written 1 references" in run(link, "-t", "0", "-r", "1", values=["1"])[1]
    out, _ = run(link, "-t", "4", "-r", "0")
    assert signed(out[0]) == -99
    out, _ = run(link, "-t", "4:float", "-B", "-r", "8")
    assert out[8] == "-2.5"
    out, _ = run(link, "-t", "0", "-r", "0", "-c", "2")
    assert (out[0], out[1]) == ("0", "1")
    # The ro mirrors, one task period later.
    time.sleep(0.05)
    out, text = run(link, "-t", "3:int", "-B", "-r", "2")
    assert out[2] == "-1999999", text
    out, _ = run(link, "-t", "3:float", "-B", "-r", "6")
    assert out[6] == "-2.5"
    out, _ = run(link, "-t", "1", "-r", "0", "-c", "2")
    assert (out[0], out[1]) == ("0", "1")
    # Exceptions.
    assert "Illegal data address" in run(link, "-t", "4", "-r", "101")[1]        # one past the end
    assert "Illegal data address" in run(link, "-t", "3", "-r", "10")[1]
    assert "Illegal data address" in run(link, "-t", "0", "-r", "2")[1]
    assert "Illegal data value" in run(link, "-t", "4", "-r", "0", values=["101"])[1]
    assert "Illegal data value" in run(link, "-t", "4:float", "-B", "-r", "8", values=["1000"])[1]
    out, _ = run(link, "-t", "4", "-r", "0")
    assert signed(out[0]) == -99                                                   # unchanged


def _addr(smap: dict, name: str) -> int:
    return next(i["address"] for i in smap["items"] if i["name"] == name)


@on_boards
def test_pt100_sensor_over_rtu(builds, firmware):
    b = builds("pt100_sensor")
    smap = json.loads(b.map.read_text())
    fw = firmware(b.exe, tcp=False)
    link = rtu_args(fw, 17, 19200)
    out, text = run(link, "-t", "4", "-r", str(_addr(smap, "cal_gain")), "-c", "3")
    assert [signed(out[k]) for k in range(3)] == [1000, 0, 800], text
    assert "Written 1 references" in run(link, "-t", "4", "-r", str(_addr(smap, "cal_offset")), values=[str(65536 - 25)])[1]
    out, _ = run(link, "-t", "4", "-r", "1")
    assert signed(out[1]) == -25
    assert "Illegal data value" in run(link, "-t", "4", "-r", "0", values=["2001"])[1]   # cal_gain 500..2000
    out, text = run(link, "-t", "3", "-r", "0", "-c", "4")                            # temperature, t_min, ...
    assert len(out) == 4, text
    out, text = run(link, "-t", "1", "-r", str(_addr(smap, "alarm")))
    assert out[0] in ("0", "1"), text
    assert "Illegal data address" in run(link, "-t", "4", "-r", "3")[1]
    assert "Illegal data address" in run(link, "-t", "3", "-r", "4")[1]
    assert "Illegal data address" in run(link, "-t", "1", "-r", "1")[1]


@on_boards
def test_pneumatic_cylinder_over_rtu(builds, firmware):
    b = builds("pneumatic_cylinder")
    smap = json.loads(b.map.read_text())
    fw = firmware(b.exe, tcp=False)
    link = rtu_args(fw, 5, 19200)
    target = _addr(smap, "target")
    out, text = run(link, "-t", "4", "-r", str(target), "-c", "3")
    assert [signed(out[target + k]) for k in range(3)] == [900, 400, 20], text
    timeout = _addr(smap, "timeout")
    out, _ = run(link, "-t", "4:int", "-B", "-r", str(timeout))
    assert out[timeout] == "2000"                                     # time param: two registers, ms
    assert "Written 1 references" in run(link, "-t", "4:int", "-B", "-r", str(timeout), values=["3500"])[1]
    assert "Illegal data value" in run(link, "-t", "4:int", "-B", "-r", str(timeout), values=["50"])[1]
    start = _addr(smap, "start_cmd")
    assert "Written 1 references" in run(link, "-t", "0", "-r", str(start), values=["1"])[1]
    out, _ = run(link, "-t", "0", "-r", "0", "-c", "2")
    assert out[start] == "1"
    cycles = _addr(smap, "cycles")
    out, text = run(link, "-t", "3:int", "-B", "-r", str(cycles))
    assert int(out[cycles]) >= 0, text
    out, _ = run(link, "-t", "1", "-r", "0")
    assert out[0] in ("0", "1")                                       # alarm
    assert "Illegal data address" in run(link, "-t", "4", "-r", "5")[1]   # target, kp, ki, timeout x2: 5 is past
