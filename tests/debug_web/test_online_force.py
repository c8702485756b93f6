"""Forcing and conditional breakpoints on the online mode's page
(docs/online.md, "Forcing and conditional breakpoints"), against
pneumatic_cylinder on its example stimulus: `end_out.level` picked on the
diagram and forced from the page holds across instants (the device trace
shows it), is drawn as forced and listed until released from the list, and
its release restores the stimulus; a condition set from the page halts
where the console's does and the page names it with its file:line and ms
(host board and the AVR in simavr); over conditions drawn by hypothesis the
page's breakpoint halts at the instant the console's property test
predicts from the un-halted trace; over drawn values a scaled item is
forced and compared in its engineering units."""

from __future__ import annotations

import time

import pytest
from hypothesis import HealthCheck, assume, given, settings, strategies as st

from debug_testlib import ROOT, Firmware, board, builds, firmware  # noqa: F401 (fixtures)
from onlinelib import OnlineServer, wait_for
from test_force_conditions import (DURATION_US, PY_OPS, STIMULUS, TICK_US, draw_condition, stimulus_at, trace_rows,
                                   value_at)
from test_online_page import open_page

END_OUT = "end_out.level"
SCREENSHOT = ROOT / "docs" / "images" / "online_force.png"


def drawn_with(server, name: str) -> str:
    """The id of a drawing's element (not a breakpoint's place) that shows item `name`."""
    ident = next(it["id"] for it in server.model()["items"] if it["name"] == name)
    return next(el for el, info in sorted(server.model()["elements"].items())
                if ident in info["items"] and not info["point"])


def set_condition(browser, name: str, op: str, value: str) -> None:
    browser.js("document.getElementById('when-item').value = arguments[0];"
               "document.getElementById('when-op').value = arguments[1];"
               "document.getElementById('when-value').value = arguments[2];", name, op, value)
    browser.button("#when-form button[type='submit']")


def halted(browser, what: str) -> dict:
    return wait_for(lambda: (s := browser.last()) and s["halted"] and s["why"] == "breakpoint" and s, 30, what)


@pytest.mark.parametrize("board", ["host", "avr"], indirect=True)
def test_a_forced_sensor_holds_and_a_condition_halts_from_the_page(board, builds, firmware, online, browser):
    fw = firmware(builds["pneumatic_cylinder"], "--stimulus", str(STIMULUS), duration="600ms")
    server = online(fw.map_path, str(fw.link), model=None)
    open_page(browser, server)
    assert browser.js("return document.getElementById('force-none').hidden") is True  # this firmware has slots

    # picked on the diagram (a click on the device plots it and picks it), forced from the form
    element = drawn_with(server, END_OUT)
    browser.click(element)
    assert browser.js("return document.getElementById('force-item').value") == END_OUT
    browser.js("document.getElementById('force-value').value = '1'")
    browser.button("#force-form button[type='submit']")
    wait_for(lambda: browser.text("#forced-list") == "end_out.level = true (forced) ✕", 10, "the forced list")
    assert "from now" in browser.text("#msg")  # halted at an instant: at once
    wait_for(lambda: "forced" in browser.js("return document.getElementById(arguments[0]).getAttribute('class')",
                                            element), 10, "the device drawn as forced")
    assert "true (forced)" in browser.js("return document.getElementById(arguments[0])"
                                         ".querySelector('text.el-value').textContent", element)
    assert [f["name"] for f in server.state(10**9)["link"]["forced"]] == [END_OUT]
    assert browser.text("#scope-list") == "end_out.level (forced) ✕"  # the click plotted it too

    # a condition from the page: halts where the console's does (tests/debug/test_force_conditions.py)
    set_condition(browser, "cycles", ">=", "1")
    wait_for(lambda: browser.text("#bp-list") == "when cycles >= 1 (hit 0) ✕", 10, "the condition listed")
    browser.button("#run")
    at = fw.map.item("cycles").location
    last = halted(browser, "the halt on the condition")
    assert (last["tick"], last["ms"], last["location"]) == (6, 30.0, at), last
    slot = server.state(10**9)["link"]["breakpoints"][0]["slot"]
    assert last["at"] == f"breakpoint {slot} when cycles >= 1"
    wait_for(lambda: browser.text("#halt-at") == f"at breakpoint {slot} when cycles >= 1 ({at})", 10, "the halt shown")
    assert browser.text("#clock").startswith("30 ms")
    wait_for(lambda: browser.text("#bp-list") == "when cycles >= 1 (hit 1) ✕", 10, "the hit counted")
    if board == "host":  # docs/online.md's picture: the forced sensor and the halt on the condition
        for _ in range(2):
            browser.button("#zoom-in")
        browser.js("window.scrollTo(0, 0); const pane = document.getElementById('diagram');"
                   "const p = pane.getBoundingClientRect(), r = document.getElementById(arguments[0])"
                   ".getBoundingClientRect(); pane.scrollBy(r.left - p.left - 200, r.top - p.top - 150);", element)
        time.sleep(0.3)
        browser.driver.save_screenshot(str(SCREENSHOT))
        browser.button("#zoom-fit")

    # released from the list, the condition deleted from it: the stimulus again
    browser.button("#forced-list button")
    wait_for(lambda: browser.text("#forced-list") == "", 10, "the release")
    assert browser.text("#scope-list") == "end_out.level ✕"
    wait_for(lambda: "forced" not in browser.js("return document.getElementById(arguments[0]).getAttribute('class')",
                                                element), 10, "the device drawn as not forced")
    browser.button("#bp-list button")
    wait_for(lambda: browser.text("#bp-list") == "", 10, "the condition deleted")
    browser.button("#run")
    status, _, err = fw.wait_exit(timeout=60)
    assert status == 0, err
    rows = trace_rows(fw.trace)
    assert all(value_at(rows, END_OUT, t) == "1" for t in range(0, 30001, TICK_US))
    assert stimulus_at(END_OUT, 30000) == "0"
    for t in range(35000, 600000, TICK_US):
        assert value_at(rows, END_OUT, t) == stimulus_at(END_OUT, t), t
    assert browser.console_errors() == []


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture],
          derandomize=True)
@given(data=st.data())
def test_a_condition_from_the_page_halts_where_the_trace_predicts(builds, browser, tmp_path_factory, data):
    exe = builds["pneumatic_cylinder"]
    name, op, value, expected = draw_condition(data, exe, tmp_path_factory)
    assume(expected is not None)  # a condition that never holds lets the run end: nothing to show
    fw = Firmware(exe, tmp_path_factory.mktemp("run"), "--stimulus", str(STIMULUS),
                  duration=f"{DURATION_US // 1000}ms")
    server = OnlineServer(fw.map_path, str(fw.link)).start()
    try:
        open_page(browser, server)
        set_condition(browser, name, op, str(value))
        wait_for(lambda: (browser.text("#bp-list") or "").startswith(f"when {name} {op} "), 10, "the condition")
        browser.button("#run")
        last = halted(browser, f"the halt when {name} {op} {value}")
        assert last["tick"] == expected, (name, op, value, last)
        assert last["location"] == fw.map.item(name).location
        wait_for(lambda: f" when {name} {op} " in (browser.text("#halt-at") or ""), 10, "the halt shown")
        assert browser.text("#clock").startswith(f"{expected * TICK_US / 1000:g} ms")
    finally:
        server.stop()
        fw.stop()


def test_a_firmware_without_slots_says_so_in_place_of_the_controls(browser, online, tmp_path):
    """blink asking for no slots (`force 0 conditions 0`, what the
    ATmega328P gets by default): HELLO reports none, the page shows the
    console's words instead of the forms, and the API refuses (409)
    without asking the target."""
    from debug_testlib import EXAMPLES, build

    from easylab.host_tools.debug_console import no_slots

    model = tmp_path / "blink.elab"
    model.write_text((EXAMPLES / "blink.elab").read_text().replace(
        "debug on uart0 baud 115200", "debug on uart0 baud 115200 force 0 conditions 0"))
    fw = Firmware(build(model, tmp_path / "build"), tmp_path)
    try:
        server = online(fw.map_path, str(fw.link), model=model)
        browser.get("about:blank")  # the last test's page stops polling its server
        browser.console_errors()  # and its messages are dropped
        browser.get(server.url)
        wait_for(lambda: browser.js("return !document.getElementById('force-none').hidden"), 20, "the no-slots note")
        assert browser.text("#force-none") == no_slots("forcing", "force")
        assert browser.text("#when-none") == no_slots("conditional breakpoints", "conditions")
        assert browser.js("return [document.getElementById('force-form').hidden,"
                          "document.getElementById('when-form').hidden]") == [True, True]
        writable = next(it["name"] for it in server.model()["items"] if it["writable"])
        r = server.api("POST", "/api/force", {"name": writable, "value": "1"})
        assert r.status == 409 and "`debug on ... force N`" in r.json()["error"]
        r = server.api("POST", "/api/breakpoint", {"when": {"name": writable, "op": "==", "value": "1"}})
        assert r.status == 409 and "`debug on ... conditions N`" in r.json()["error"]
        assert browser.console_errors() == []
    finally:
        fw.stop()


@pytest.fixture
def pt100(builds, firmware, online):
    """pt100_sensor (scaled params and vars, 0.1 degC) halted on the host
    board, its page's server."""
    fw = firmware(builds["pt100_sensor"])
    return online(fw.map_path, str(fw.link), model=None)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture],
          derandomize=True)
@given(stored=st.integers(-500, 500), op=st.sampled_from(sorted(PY_OPS)), limit=st.integers(-2000, 8500))
def test_forced_values_and_constants_are_in_engineering_units(pt100, stored, op, limit):
    """What the page sends is in the item's units (cal_offset and
    temperature: scale 0.1 "degC"); the target holds and compares the
    stored integers, and lists them back (FORCE_LIST, BP_LIST) as the page
    shows them."""
    from easylab.host_tools.units import Scale

    tenth = Scale.of("0.1")
    text = tenth.show(stored)
    r = pt100.api("POST", "/api/force", {"name": "cal_offset", "value": text})
    assert r.status == 200 and r.json()["shown"] == f"{text} degC", r.json()
    assert [(f["name"], f["value"], f["shown"]) for f in pt100.state(10**9)["link"]["forced"]] == \
        [("cal_offset", stored, f"{text} degC")]
    constant = tenth.show(limit)
    r = pt100.api("POST", "/api/breakpoint", {"when": {"name": "temperature", "op": op, "value": constant}})
    assert r.status == 200 and r.json()["at"] == f"when temperature {op} {constant} degC", r.json()
    listed = pt100.state(10**9)["link"]["breakpoints"]
    assert [(b["at"], b["location"]) for b in listed] == \
        [(f"when temperature {op} {constant} degC", "examples/pt100_sensor.elab:15")]
    assert pt100.api("POST", "/api/breakpoint", {"slot": "all"}).status == 200
    r = pt100.api("POST", "/api/force", {"name": "cal_offset", "value": text + "5"})  # a finer digit than 0.1
    assert r.status == 400 and "not a multiple of the scale 0.1" in r.json()["error"], r.json()
