"""The service panel in a real browser: headless Chromium on the page that
`easylab-service web` serves for a host-board pt100_sensor over Modbus TCP
(one device, one panel and one browser for the module; the tests follow
one another on them).

Set EASYLAB_SCREENSHOT_DIR=docs/images to refresh the screenshot of
docs/service.md (service-panel.png).
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from weblib import device_values, item_text, set_in_page, wait_for

PARAMS = ["cal_gain", "cal_offset", "alarm_high"]
MEASUREMENTS = ["temperature", "t_min", "t_max", "t_mean", "alarm"]


def test_every_item_is_listed_by_kind_with_unit_range_and_persist(bench):
    b = bench.browser
    groups = b.js("return [...document.querySelectorAll('.group')].map(g => "
                  "[g.querySelector('h2').textContent, [...g.querySelectorAll('.item')].map(i => i.dataset.item)])")
    assert groups == [["Measurements", MEASUREMENTS], ["Parameters", PARAMS]]
    assert item_text(bench, "cal_offset", ".unit") == "degC"  # unit "degC" scale 0.1: engineering units
    assert item_text(bench, "cal_offset", ".meta") == "int16 · range -50.0..50.0"
    assert item_text(bench, "cal_gain", ".meta") == "int16 · range 500..2000"
    assert item_text(bench, "temperature", ".meta") == "int16"
    for name in PARAMS:
        assert item_text(bench, name, ".badge") == "persist"
        assert b.js(f"return !!document.querySelector('[data-item=\"{name}\"] input')")
    for name in MEASUREMENTS:
        assert b.js(f"return document.querySelector('[data-item=\"{name}\"] input')") is None
        assert item_text(bench, name, ".badge") == "ro"
    assert b.text("#model") == "pt100_sensor" and b.text("#title") == "PT100 smart temperature sensor"
    # A phone's width: nothing sticks out sideways.
    assert b.js("return document.documentElement.scrollWidth <= window.innerWidth")
    assert b.js("return window.innerWidth") == 390


def test_temperature_updates_live_and_is_plotted(bench, tmp_path):
    b = bench.browser
    seen: set[str] = set()
    wait_for(lambda: seen.add(item_text(bench, "temperature")) or len(seen) >= 4, timeout=15,
             what="four different temperatures on the page")
    shown = [float(v) for v in seen if v != "–"]
    assert all(19.0 <= v <= 31.0 and v == round(v, 1) for v in shown), shown  # the ramp: about 20..30 degC
    assert 190 <= device_values(bench, "temperature")["temperature"] <= 310  # stored: 0.1 degC
    # The first measurement is plotted without asking; another one on request.
    wait_for(lambda: b.js("return easylabPanel.charts[0].plot.data[0].length") >= 30, timeout=15,
             what="30 points in the temperature plot")
    # Another item joins the same plot (several series on one plot).
    b.find('[data-item="t_mean"] button.plot-toggle').click()
    assert b.js("return easylabPanel.charts.map(c => c.names)") == [["temperature", "t_mean"]]
    assert b.find('[data-item="t_mean"] button.plot-toggle').get_attribute("aria-pressed") == "true"
    plotted = b.js("const p = easylabPanel.charts[0].plot; return [p.data[0].length, p.data[1].at(-1), p.series.length]")
    assert plotted[0] >= 30 and 19.0 <= plotted[1] <= 31.0 and plotted[2] == 3
    assert b.js("return document.querySelectorAll('.plot canvas').length") == 1
    # The choice of plots outlives a reload of the page.
    b.get(bench.panel.url)
    wait_for(lambda: b.js("return easylabPanel.charts && easylabPanel.charts.map(c => c.names)")
             == [["temperature", "t_mean"]], what="plots after reload")
    wait_for(lambda: b.js("return easylabPanel.charts[0].plot.data[0].length") >= 40, timeout=15,
             what="the plot to fill from the server's history")
    # No console error, no content-security-policy violation (uPlot included).
    problems = [e for e in b.console() if "Content Security Policy" in e["message"]
                or (e["level"] == "SEVERE" and bench.panel.base in e["message"])]
    assert problems == []
    shot = tmp_path / "service-panel.png"
    b.screenshot(shot)
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20000
    if os.environ.get("EASYLAB_SCREENSHOT_DIR"):
        shutil.copyfile(shot, Path(os.environ["EASYLAB_SCREENSHOT_DIR"]) / "service-panel.png")


def test_cal_offset_write_shows_in_the_device_trace(bench):
    b = bench.browser
    set_in_page(bench, "cal_offset", "2.5")
    wait_for(lambda: item_text(bench, "cal_offset", ".msg") == "set: cal_offset = 2.5 degC", what="the write")
    assert item_text(bench, "cal_offset") == "2.5"
    assert device_values(bench, "cal_offset") == {"cal_offset": 25}
    # A clean stop writes the whole trace: the write is in it, at one instant.
    bench.fw.stop()
    with (bench.work / "trace.csv").open() as f:
        offsets = [int(row["cal_offset"]) for row in csv.DictReader(f)]
    assert offsets[0] == 0 and offsets[-1] == 25
    assert sorted(set(offsets)) == [0, 25] and offsets.index(25) > 0
    wait_for(lambda: b.text("#link-state") == "device lost", what="the page to see the device gone")
    # Started again on its port: the page reconnects, the persist param kept its value.
    bench.fw = bench.devices.start(port=bench.fw.port, trace="trace2.csv")
    wait_for(lambda: b.text("#link-state") == "connected", timeout=15, what="the page to reconnect")
    wait_for(lambda: item_text(bench, "cal_offset") == "2.5", what="cal_offset after the restart")


def test_out_of_range_value_is_refused_in_words(bench):
    b = bench.browser
    before = device_values(bench, "cal_offset")["cal_offset"]
    # The page checks the map's range before sending: nothing leaves the page.
    b.js("window.postsSent = 0; const f = window.fetch; window.fetch = (url, init) => "
         "{ if (init && init.method === 'POST') window.postsSent += 1; return f(url, init); };")
    set_in_page(bench, "cal_offset", "-60")
    wait_for(lambda: "outside the range" in (item_text(bench, "cal_offset", ".msg") or ""), what="the range message")
    assert item_text(bench, "cal_offset", ".msg") == "-60 is outside the range of cal_offset (-50.0..50.0 degC): not sent"
    assert "invalid" in b.find('[data-item="cal_offset"] input').get_attribute("class")
    assert b.js("return window.postsSent") == 0
    # Sent without that check (as any client of the panel may), the device
    # itself refuses: its Modbus exception in words.
    exceptions = bench.panel.link()["stats"]["exceptions"]
    assert b.js("return easylabPanel.send('cal_offset', '-60')") is False
    msg = item_text(bench, "cal_offset", ".msg")
    assert msg.startswith("Refused by the device: illegal data value (exception 03)")
    assert "-60.0 is outside the range of 'cal_offset' (-50.0..50.0 degC): the device refused it" in msg
    assert "error" in b.find('[data-item="cal_offset"] .msg').get_attribute("class")
    assert bench.panel.link()["stats"]["exceptions"] == exceptions + 1
    assert device_values(bench, "cal_offset")["cal_offset"] == before


def test_backup_and_restore_round_trip(bench, tmp_path):
    b = bench.browser
    saved = b.downloads / "pt100_sensor-params.json"
    if saved.exists():
        saved.unlink()
    b.find("#backup-button").click()
    wait_for(lambda: saved.exists() and saved.stat().st_size > 0, what="the backup download")
    doc = json.loads(saved.read_text())
    assert doc["format"] == 1 and doc["model"] == "pt100_sensor"
    assert doc["params"] == device_values(bench, *PARAMS)
    assert b.text("#backup-msg") == "backup of 3 params saved as pt100_sensor-params.json"
    # Change two params, then restore the file through the page.
    set_in_page(bench, "cal_gain", "1500")
    wait_for(lambda: item_text(bench, "cal_gain", ".msg") == "set: cal_gain = 1500 1/1000", what="cal_gain write")
    set_in_page(bench, "alarm_high", "95")
    wait_for(lambda: item_text(bench, "alarm_high", ".msg") == "set: alarm_high = 95.0 degC", what="alarm_high")
    assert device_values(bench, "cal_gain", "alarm_high") == {"cal_gain": 1500, "alarm_high": 950}
    b.find("#restore-file").send_keys(str(saved))
    wait_for(lambda: b.js("return !document.getElementById('restore-confirm').hidden"), what="the restore question")
    assert b.text("#restore-what") == "Write 3 params of model pt100_sensor from pt100_sensor-params.json to the device?"
    b.find("#restore-go").click()
    wait_for(lambda: b.text("#backup-msg") == "restored 3 of 3 params", what="the restore")
    assert device_values(bench, *PARAMS) == doc["params"]
    wait_for(lambda: item_text(bench, "cal_gain") == str(doc["params"]["cal_gain"]), what="the page to follow")
    # The file is the command-line tool's backup format: it restores it too.
    proc = subprocess.run([sys.executable, "-m", "easylab.host_tools.service_cli", "--map", str(bench.map), "--tcp",
                           f"127.0.0.1:{bench.fw.port}", "restore", str(saved)], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0 and "restored 3 of 3 params" in proc.stdout, proc.stderr


def test_device_killed_and_restarted_is_reconnected(bench):
    b = bench.browser
    connects = bench.panel.link()["connects"]
    bench.fw.kill()
    wait_for(lambda: b.text("#link-state") == "device lost", what="the page to see the device gone")
    banner = b.find("#banner")
    assert banner.is_displayed()
    assert banner.text.startswith(f"The device at 127.0.0.1:{bench.fw.port} went away:")
    assert "reconnects by itself" in banner.text
    wait_for(lambda: f"cannot connect to 127.0.0.1:{bench.fw.port}" in b.text("#link-message"),
             what="the reason on the page")
    assert "stale" in b.find('[data-item="temperature"]').get_attribute("class")
    lost = bench.panel.link()["stats"]["lost"]
    assert lost >= 1
    bench.fw = bench.devices.start(port=bench.fw.port, trace="trace3.csv")
    wait_for(lambda: b.text("#link-state") == "connected", timeout=15, what="the page to reconnect")
    assert not b.find("#banner").is_displayed()
    assert b.text("#link-message") == f"connected again to 127.0.0.1:{bench.fw.port} (model pt100_sensor)"
    seen: set[str] = set()
    wait_for(lambda: seen.add(item_text(bench, "temperature")) or len(seen) >= 3, timeout=15,
             what="the temperature to move again")
    assert "stale" not in b.find('[data-item="temperature"]').get_attribute("class")
    assert bench.panel.link()["connects"] == connects + 1
    assert f"{connects + 1} connects" in b.text("#link-counts")
