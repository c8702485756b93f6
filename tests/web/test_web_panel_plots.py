"""The service panel's plots and values in a real browser (headless Chromium
on the page of `easylab-service web`, a host-board pt100_sensor over Modbus
TCP): values in engineering units (the page's BigInt arithmetic against the
tools' own, on generated scales and values, and a round trip through the
device), a device outage drawn as a gap, connection messages cleared when
it is back, a mark where a write happened, pause and zoom, several series
on one plot with bools drawn as states and alarms styled, the CSV of a
plot, and negative values typed on a phone's keyboard."""

from __future__ import annotations

import csv
import re
from decimal import Decimal
from fractions import Fraction

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from weblib import device_values, item_text, set_in_page, wait_for

LIMITS = {"int8": (-128, 127), "uint8": (0, 255), "int16": (-32768, 32767), "uint16": (0, 65535),
          "int32": (-2 ** 31, 2 ** 31 - 1), "uint32": (0, 2 ** 32 - 1)}
SCALES = st.builds(lambda digits, decimals: Fraction(digits, 10 ** decimals), st.integers(1, 999_999),
                   st.integers(0, 9)).filter(lambda f: Fraction(1, 10 ** 9) <= f <= 10 ** 6)

CHART_OF = "const c = easylabPanel.charts.find(c => c.names.includes(arguments[0]));"


def click(bench, css: str) -> None:
    """Click an element as a person does, first scrolled to the middle of the
    screen (the page's sticky header covers the top)."""
    element = bench.browser.find(css)
    bench.browser.js("arguments[0].scrollIntoView({block: 'center'})", element)
    element.click()


def index_of(bench, name: str) -> int:
    return bench.browser.js("return easylabPanel.rows.get(arguments[0]).index", name)


def samples_seen(bench) -> int:
    return bench.browser.js("return easylabPanel.times.length")


def decimal(value: Fraction) -> str:
    return format(Decimal(value.numerator) / Decimal(value.denominator), "f")


# ---------------------------------------------------------------- engineering units


def test_the_page_shows_and_reads_values_as_the_tools_do(bench):
    """Generated scales, types and stored values: the page's text of a value
    is the tools' (host_tools/units.py), it reads that text back to the same
    stored value, and refuses text between two stored values or beyond the
    type before sending."""
    from easylab.host_tools.service_map import ServiceItem
    from easylab.host_tools.units import Scale
    b = bench.browser

    @settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(scale=SCALES, type_name=st.sampled_from(sorted(LIMITS)), data=st.data())
    def check(scale, type_name, data):
        it = ServiceItem(0, "p", "param", "holding", 0, 2, type_name, "u", None, "rw", False, Scale.of(decimal(scale)))
        lo, hi = LIMITS[type_name]
        stored = data.draw(st.one_of(st.integers(lo, hi), st.sampled_from([lo, hi, 0])))
        text = it.format(stored)
        between = decimal(Fraction(Decimal(text)) + scale / 2)
        page = b.js("""const u = easylabPanel.units, it = arguments[0];
            const back = u.storedOf(it, arguments[2]);
            return [u.format(it, arguments[1]), String(back.stored), u.checkValue(it, arguments[2]),
                    u.storedOf(it, arguments[3]).error || null, u.checkValue(it, arguments[4])];""",
                    {"name": "p", "type": type_name, "scale": it.scale.text(), "unit": "u", "range": None},
                    stored, text, between, it.format(hi + 1))
        shown, back, check_text, between_error, beyond = page
        assert shown == text
        assert int(back) == stored and it.parse(shown) == stored
        assert check_text is None
        if it.scale.is_one:
            assert between_error is None or "not a multiple" in between_error
        else:
            assert between_error == (f"{between} is not a multiple of the scale {it.scale.text()} of p: "
                                     f"it cannot be stored exactly, not sent")
        assert beyond.startswith(f"{it.format(hi + 1)} is outside the range of p (")
    check()


def test_a_scaled_value_goes_to_the_device_and_back(bench):
    """cal_offset (int16, unit "degC" scale 0.1, range -500..500 stored):
    typed in degC on the page, a phone's decimal comma included, stored on
    the device as tenths, shown again as typed."""
    from easylab.host_tools.service_map import load_map
    it = load_map(bench.map).item("cal_offset")
    b = bench.browser

    @settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(stored=st.integers(-500, 500), comma=st.booleans())
    def check(stored, comma):
        text = it.format(stored)
        set_in_page(bench, "cal_offset", text.replace(".", ",") if comma else text)
        wait_for(lambda: item_text(bench, "cal_offset", ".msg") == f"set: cal_offset = {text} degC",
                 what=f"the write of {text}")
        assert device_values(bench, "cal_offset") == {"cal_offset": stored}
        assert item_text(bench, "cal_offset") == text
    check()
    set_in_page(bench, "cal_offset", "0")
    wait_for(lambda: item_text(bench, "cal_offset", ".msg") == "set: cal_offset = 0.0 degC", what="cal_offset back")
    # Between two tenths: refused by the page, and by the server for any client.
    set_in_page(bench, "cal_offset", "2.55")
    assert item_text(bench, "cal_offset", ".msg") == ("2.55 is not a multiple of the scale 0.1 of cal_offset: "
                                                       "it cannot be stored exactly, not sent")
    reply = bench.panel.api("POST", "/api/write", {"name": "cal_offset", "value": "2.55"})
    assert reply.status == 400
    assert reply.json()["error"] == "'cal_offset': 2.55 is not a multiple of the scale 0.1: it cannot be stored exactly"
    assert b.js("return easylabPanel.rows.get('temperature').it.scale") == "0.1"


def test_negative_values_on_a_phone_keyboard(bench):
    b = bench.browser
    field = b.find('[data-item="cal_offset"] input')
    assert (field.get_attribute("inputmode"), field.get_attribute("enterkeyhint")) == ("decimal", "send")
    assert field.get_attribute("autocapitalize") == "none" and field.get_attribute("type") == "text"
    # cal_gain cannot be negative (500..2000): digits only, no sign key.
    assert b.find('[data-item="cal_gain"] input').get_attribute("inputmode") == "numeric"
    assert b.js("return document.querySelector('[data-item=\"cal_gain\"] button.sign')") is None
    field.clear()
    field.send_keys("1,5")
    sign = b.find('[data-item="cal_offset"] button.sign')
    sign.click()
    assert field.get_attribute("value") == "-1,5"
    sign.click()
    sign.click()
    b.find('[data-item="cal_offset"] button.set').click()
    wait_for(lambda: item_text(bench, "cal_offset", ".msg") == "set: cal_offset = -1.5 degC", what="the write")
    assert device_values(bench, "cal_offset") == {"cal_offset": -15}


# ---------------------------------------------------------------- marks, pause, zoom, series, CSV


def test_a_write_is_marked_on_the_plots(bench):
    b = bench.browser
    wait_for(lambda: b.js(f"{CHART_OF} return c && c.plot.data[0].length > 5", "temperature"), timeout=15,
             what="the temperature plot")
    before = b.js("return easylabPanel.marks.length")
    set_in_page(bench, "cal_offset", "0.7")
    wait_for(lambda: item_text(bench, "cal_offset", ".msg") == "set: cal_offset = 0.7 degC", what="the write")
    mark = b.js("return easylabPanel.marks.at(-1)")
    assert b.js("return easylabPanel.marks.length") == before + 1
    assert (mark["name"], mark["text"]) == ("cal_offset", "0.7 degC")
    # The mark stands where the write happened: within the samples around it, drawn on the plot.
    wait_for(lambda: b.js(f"{CHART_OF} return c.plot.scales.x.max", "temperature") > mark["t"], timeout=10,
             what="samples after the write")
    assert b.js(f"{CHART_OF} return c.plot.scales.x.min", "temperature") < mark["t"]
    wait_for(lambda: b.js(f"{CHART_OF} return c.marksDrawn", "temperature") >= 1, what="the mark drawn")


def test_plots_pause_zoom_and_follow_again(bench):
    from selenium.webdriver.common.action_chains import ActionChains
    b = bench.browser
    wait_for(lambda: b.js(f"{CHART_OF} return c.plot.data[0].length", "temperature") > 20, timeout=15,
             what="20 samples plotted")
    click(bench, "#plot-pause")
    assert b.find("#plot-pause").get_attribute("aria-pressed") == "true" and b.text("#plot-pause") == "Resume"
    shown = b.js(f"{CHART_OF} return c.plot.data[0].length", "temperature")
    seen = samples_seen(bench)
    wait_for(lambda: samples_seen(bench) >= seen + 4, what="samples coming in while paused")
    assert b.js(f"{CHART_OF} return c.plot.data[0].length", "temperature") == shown
    click(bench, "#plot-pause")
    wait_for(lambda: b.js(f"{CHART_OF} return c.plot.data[0].length", "temperature") > shown, what="the plot again")
    # Dragging across a plot zooms in on that span; it stays while samples come in.
    over = b.find('.plot .u-over')
    b.js("arguments[0].scrollIntoView({block: 'center'})", over)
    width = over.size["width"]
    full = b.js(f"{CHART_OF} const x = c.plot.scales.x; return x.max - x.min", "temperature")
    ActionChains(b.driver).move_to_element_with_offset(over, -width // 4, 0).click_and_hold() \
        .move_by_offset(width // 3, 0).release().perform()
    wait_for(lambda: b.js(f"{CHART_OF} return c.zoomed", "temperature"), what="the zoom")
    span = b.js(f"{CHART_OF} const x = c.plot.scales.x; return [x.min, x.max]", "temperature")
    assert span[1] - span[0] < full * 0.6
    seen = samples_seen(bench)
    wait_for(lambda: samples_seen(bench) >= seen + 4, what="more samples")
    assert b.js(f"{CHART_OF} const x = c.plot.scales.x; return [x.min, x.max]", "temperature") == span
    # The CSV of a zoomed plot is what it shows: its span, in engineering units.
    text = b.js(f"{CHART_OF} return easylabPanel.csvOf(c)", "temperature")
    rows = list(csv.DictReader(text.splitlines()))
    assert rows and all(span[0] <= float(r["unix_s"]) <= span[1] for r in rows)
    assert all(re.fullmatch(r"-?\d+\.\d", r["temperature [degC]"]) for r in rows), rows[:3]
    # "Live" follows the newest samples again.
    click(bench, "#plot-live")
    assert not b.js(f"{CHART_OF} return c.zoomed", "temperature")
    wait_for(lambda: b.js(f"{CHART_OF} return c.plot.scales.x.max", "temperature") > span[1], what="following again")


def test_several_series_bools_as_states_alarms_styled_and_csv(bench):
    from selenium.webdriver.support.ui import Select
    b = bench.browser
    chart = "const c = easylabPanel.charts[0];"
    for name in ("t_max", "alarm"):
        Select(b.find(".plot select.add")).select_by_value(name)
    names = b.js(f"{chart} return c.names")
    assert names[-2:] == ["t_max", "alarm"] and "temperature" in names
    scales = b.js(f"{chart} return c.plot.series.slice(1).map(s => s.scale)")
    assert scales == ["state" if n == "alarm" else "y" for n in names]
    assert b.js(f"{chart} return c.plot.axes.map(a => a.scale)") == ["x", "y", "state"]
    assert b.find('.plot [data-series="alarm"]').get_attribute("class") == "series alarm"
    # The alarm on: its card and its value in the alarm style.
    assert "alarm" in b.find('[data-item="alarm"]').get_attribute("class").split()
    set_in_page(bench, "alarm_high", "10")
    wait_for(lambda: "alarm-on" in b.find('[data-item="alarm"]').get_attribute("class"), timeout=10,
             what="the alarm on")
    assert item_text(bench, "alarm") == "on"
    wait_for(lambda: b.js(f"{chart} const k = c.names.indexOf('alarm') + 1; return c.plot.data[k].at(-1)") == 1,
             what="the alarm's state plotted on")
    set_in_page(bench, "alarm_high", "80")
    wait_for(lambda: "alarm-on" not in b.find('[data-item="alarm"]').get_attribute("class"), timeout=10,
             what="the alarm off")
    # The plot's CSV, downloaded by its button.
    saved = b.downloads / "pt100_sensor-plot-1.csv"
    if saved.exists():
        saved.unlink()
    click(bench, ".plot button.csv")
    wait_for(lambda: saved.exists() and saved.stat().st_size > 0, what="the CSV download")
    rows = list(csv.DictReader(saved.read_text().splitlines()))
    assert list(rows[0]) == ["time", "unix_s", *[n + (" [degC]" if n != "alarm" else "") for n in names]]
    assert {r["alarm"] for r in rows} <= {"0", "1", ""} and "1" in {r["alarm"] for r in rows}
    assert all(r["time"].endswith("Z") for r in rows)


# ---------------------------------------------------------------- an outage


def test_an_outage_is_a_gap_and_its_messages_go_when_it_is_back(bench):
    b = bench.browser
    # A refusal that is not about the connection stays.
    set_in_page(bench, "alarm_high", "-300")
    assert "outside the range" in item_text(bench, "alarm_high", ".msg")
    bench.fw.kill()
    wait_for(lambda: b.text("#link-state") == "device lost", what="the page to see the device gone")
    set_in_page(bench, "cal_offset", "1.0")
    wait_for(lambda: item_text(bench, "cal_offset", ".msg").startswith("the device is not connected"),
             what="the refusal of a write while the device is away")
    click(bench, "#backup-button")
    wait_for(lambda: b.text("#backup-msg").startswith("no backup: the device is not connected"),
             what="the refusal of a backup")
    assert b.js("return document.querySelectorAll('.msg[data-link=\"1\"]').length") == 2
    before = samples_seen(bench)
    bench.fw = bench.devices.start(port=bench.fw.port, trace="trace-gap.csv")
    wait_for(lambda: b.text("#link-state") == "connected", timeout=15, what="the page to reconnect")
    # Back: the connection's messages are gone, the other one is still there.
    wait_for(lambda: item_text(bench, "cal_offset", ".msg") == "" and b.text("#backup-msg") == "",
             what="the connection's messages cleared")
    assert "outside the range" in item_text(bench, "alarm_high", ".msg")
    wait_for(lambda: samples_seen(bench) >= before + 5, timeout=10, what="samples after the outage")
    # One null row between the last sample before the outage and the first after it.
    k = index_of(bench, "temperature")
    times, column = b.js("return [easylabPanel.times, easylabPanel.series[arguments[0]]]", k)
    lost_at = max(t for t, v in zip(times[:before], column[:before]) if v is not None)
    gaps = [i for i, v in enumerate(column) if v is None and times[i - 1] == lost_at]
    assert len(gaps) == 1, (gaps, lost_at)
    g = gaps[0]
    assert column[g - 1] is not None and column[g + 1] is not None
    assert times[g - 1] < times[g] < times[g + 1] and times[g + 1] - times[g - 1] > 0.5
    plotted = b.js(f"{CHART_OF} const i = c.names.indexOf('temperature') + 1; "
                   "return [c.plot.data[i].slice(arguments[1] - 1, arguments[1] + 2), !!c.plot.series[i].spanGaps]",
                   "temperature", g)
    assert plotted[0][1] is None and None not in (plotted[0][0], plotted[0][2]) and plotted[1] is False
    # The server marks the first sample after a connect: a page opened later draws the gap too.
    doc = bench.panel.api("GET", "/api/samples?after=-1").json()
    assert [s.get("gap", False) for s in doc["samples"]].count(True) >= 1


# ---------------------------------------------------------------- generated models


UNITS = st.text(st.sampled_from("abcdegmsAKVW°µ/%²·-"), min_size=1, max_size=8).map(str.strip).filter(bool)


def test_generated_scales_and_units_round_trip_through_map_page_and_device(tmp_path, panel, browser):
    """Generated models (an integer type, a unit, a scale, initial values)
    built for the host board: the map carries the scale and unit, the page
    shows the initial values as the tools do, and a generated value typed
    in engineering units reaches the device as the stored integer."""
    from easylab.host_tools.modbus_link import ModbusLink
    from easylab.host_tools.service_cli import read_values
    from easylab.host_tools.service_map import load_map
    from svc_testlib import Firmware, build_model
    runs = iter(range(100))

    @settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(scale=SCALES.filter(lambda f: f != 1), type_name=st.sampled_from(sorted(LIMITS)), unit=UNITS,
           data=st.data())
    def check(scale, type_name, unit, data):
        lo, hi = LIMITS[type_name]
        initial, written = data.draw(st.integers(lo, hi)), data.draw(st.integers(lo, hi))
        work = tmp_path / f"run{next(runs)}"
        model = work / "gen.elab"
        model.parent.mkdir(parents=True)
        model.write_text(f'model gen "Generated scale"\n'
                         f'param p: {type_name} = {initial} unit "{unit}" scale {decimal(scale)} service rw\n'
                         f'var   v: {type_name} = {initial} unit "{unit}" scale {decimal(scale)} service ro\n'
                         f'modbus tcp port 1502\n')
        built = build_model(model, work / "host")
        it = load_map(built.map).item("p")
        assert (it.scale.fraction, it.unit) == (scale, unit)
        fw = Firmware(built.exe, work, rtu=False).start()
        try:
            p = panel(built.map, "--tcp", f"127.0.0.1:{fw.port}")
            browser.get(p.url)
            wait_for(lambda: browser.text('[data-item="v"] .value') == it.format(initial), timeout=15,
                     what="the initial value on the page")
            assert browser.text('[data-item="v"] .unit') == unit
            field = browser.find('[data-item="p"] input')
            field.clear()
            field.send_keys(it.format(written))
            browser.find('[data-item="p"] button.set').click()
            wait_for(lambda: browser.text('[data-item="p"] .msg') == f"set: p = {it.format(written)} {unit}",
                     what="the write")
            link = ModbusLink.tcp("127.0.0.1", fw.port, 1, 2.0)
            try:
                assert read_values(link, [it]) == {"p": written}
            finally:
                link.close()
        finally:
            fw.stop()
    check()
