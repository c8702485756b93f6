"""The service panel on the other modes that serve the service interface:
the AVR firmware (ATmega2560) in its simavr harness, Modbus RTU on a pty,
and local execution (`easylab run --modbus-tcp`). Each: the panel connects,
samples, writes and reads back, shows a refusal in words, backs up, and
reconnects to a restarted device; the page shows the values."""

from __future__ import annotations

import os
import re

import pytest

from svc_testlib import EXAMPLES, AvrFirmware, InterpFirmware, build_avr, build_interp
from weblib import wait_for


def connected(p) -> bool:
    return p.link()["state"] == "connected"


@pytest.fixture
def avr_pt100(tmp_path_factory):
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    return build_avr(EXAMPLES / "pt100_sensor.elab", tmp_path_factory.mktemp("avr_pt100"), env)


def exercise(p, browser) -> None:
    """What every mode must do: samples, a write read back, a refusal in
    words, a backup, the page."""
    wait_for(lambda: connected(p), timeout=30, what=f"the panel to connect ({p.err})")
    first = wait_for(lambda: p.api("GET", "/api/samples?after=-1").json()["samples"], what="samples")[-1]["seq"]
    wait_for(lambda: p.api("GET", f"/api/samples?after={first}").json()["samples"], what="new samples")
    assert isinstance(p.latest()["temperature"], int) and p.latest()["cal_gain"] == 1000
    r = p.api("POST", "/api/write", {"name": "cal_offset", "value": "-1.2"})   # degC: stored in tenths
    body = r.json()
    seq = body.pop("seq")
    assert body.pop("t") > 0
    assert r.status == 200 and body == {"name": "cal_offset", "value": -12, "text": "-1.2"}
    # The write came after the samples it names: every later one shows it.
    assert seq >= first + 1
    later = wait_for(lambda: p.api("GET", f"/api/samples?after={seq}").json()["samples"], what="samples after the write")
    column = [it["name"] for it in p._map()["items"]].index("cal_offset")
    assert all(s["v"][column] == -12 for s in later)
    wait_for(lambda: p.latest()["cal_offset"] == -12, what="the samples to show the write")
    r = p.api("POST", "/api/write", {"name": "cal_gain", "value": "2001"})
    assert r.status == 422 and r.json()["words"] == "illegal data value" and r.json()["exception"] == 3
    assert "2001 is outside the range of 'cal_gain' (500..2000 1/1000)" in r.json()["error"]
    r = p.api("GET", "/api/backup")
    assert r.status == 200 and r.json()["params"] == {"cal_gain": 1000, "cal_offset": -12, "alarm_high": 800}
    browser.get(p.url)
    wait_for(lambda: browser.text("#link-state") == "connected", what="the page")
    wait_for(lambda: browser.text('[data-item="cal_offset"] .value') == "-1.2", what="the value on the page")
    assert re.fullmatch(r"-?\d+\.\d", browser.text('[data-item="temperature"] .value'))


def test_avr_in_simavr_over_rtu(avr_pt100, tmp_path, panel, browser):
    fw = AvrFirmware(avr_pt100.exe, tmp_path).start()
    try:
        p = panel(avr_pt100.map, "--rtu", str(fw.rtu), "--parity", "N")     # unit 17, 19200 baud: the map's
        exercise(p, browser)
        assert p.link()["where"] == f"{fw.rtu} unit 17"
        # The harness goes away with its pty; a new one comes on the same link.
        fw.kill()
        wait_for(lambda: p.link()["state"] == "lost", what="the panel to see the device gone")
        fw = AvrFirmware(avr_pt100.exe, tmp_path, rtu_link=fw.rtu).start()
        wait_for(lambda: connected(p), timeout=30, what=f"the panel to reconnect ({p.err})")
        assert p.link()["connects"] == 2
        wait_for(lambda: p.latest()["cal_gain"] == 1000, what="samples from the new device")
    finally:
        fw.stop()


def test_local_execution_over_tcp(tmp_path, panel, browser):
    model = tmp_path / "pt100_sensor.elab"
    model.write_text((EXAMPLES / "pt100_sensor.elab").read_text() + "modbus  tcp port 1502\n")
    built = build_interp(model, tmp_path / "maps")
    fw = InterpFirmware(model, tmp_path, rtu=False).start()
    try:
        p = panel(built.map, "--tcp", f"127.0.0.1:{fw.port}")
        exercise(p, browser)
        fw.kill()
        wait_for(lambda: p.link()["state"] == "lost", what="the panel to see the run gone")
        fw = InterpFirmware(model, tmp_path, rtu=False, port=fw.port).start()
        wait_for(lambda: connected(p), timeout=30, what=f"the panel to reconnect ({p.err})")
        wait_for(lambda: p.latest()["cal_offset"] == 0, what="samples from the new run")
    finally:
        fw.stop()
