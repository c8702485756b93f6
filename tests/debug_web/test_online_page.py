"""The online mode's page in Chromium (selenium) against pneumatic_cylinder
running in real time on its slow cycle (onlinelib.SLOW_CYCLE): on the host
board the highlighted step follows the stimulus, a breakpoint set by a
click on `Extending` halts there and the page shows its file:line (and the
line in the model's text) and marks the transition Retracted -> Extending
as the one fired last, a step advances, the values on PositionControl's
edges change while it runs, the scope plots over logical time and exports
CSV, zooming in leaves what is out of sight unpolled, a write through the
form shows on the diagram (a value out of range is refused), a reset halts
at the start, the scope exports CSV and VCD, the guards show on the
transitions; against the AVR in simavr, the PIC18 in gpsim, local and
remote execution the highlight and a breakpoint. The host test saves
docs/images/online.png."""

from __future__ import annotations

import time

import pytest

from debug_testlib import ROOT, board, builds, firmware  # noqa: F401 (fixtures)
from onlinelib import MODEL_FILE, slow_cycle, wait_for

from easylab.host_tools.debug_map import DebugMap

EXTENDING_AT = f"{MODEL_FILE}:44"
CYCLE = ["step:Cylinder.Retracted", "step:Cylinder.Extending", "step:Cylinder.Extended",
         "step:Cylinder.Retracting", "step:Cylinder.Retracted"]
EDGES = ["edge:PositionControl/position.value->pos.x", "edge:PositionControl/pid.y->drive"]
SCREENSHOT = ROOT / "docs" / "images" / "online.png"


def edge_labels(browser) -> list[str]:
    return browser.js("return arguments[0].map(id => { const t = document.getElementById(id)"
                      ".querySelector('text.el-value'); return t ? t.textContent : null; })", EDGES)


def open_page(browser, server):
    browser.get("about:blank")  # the last test's page stops polling its server
    browser.console_errors()  # and its messages are dropped
    browser.get(server.url)
    wait_for(lambda: browser.last() is not None, 30, f"the first snapshot ({''.join(server.err)[-500:]})")
    assert browser.js("return document.querySelectorAll('#diagram svg g[data-point]').length") > 10


def has_cycle(seen: list[str]) -> bool:
    """True when the steps seen hold the whole cycle, in order, one after the other."""
    return any(seen[k:k + len(CYCLE)] == CYCLE for k in range(len(seen)))


def follow_the_cycle(browser, seconds: float, with_edges: bool):
    """The highlighted steps in order (repeats dropped), and the values seen on the edges."""
    seen, edges = [], [set(), set()]
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline and not has_cycle(seen):
        active = browser.active_steps()
        if active and (not seen or seen[-1] != active[0]):
            seen.append(active[0])
        if with_edges and active == ["step:Cylinder.Extending"]:
            for k, label in enumerate(edge_labels(browser)):
                edges[k].add(label)
        time.sleep(0.02)
    return seen, edges


def check_vcd(vcd: str, names: list[str], first_ms: float, tmp_path) -> None:
    """The scope's VCD opens in GTKWave's reader (vcd2fst) and comes back
    (fst2vcd) with every signal and its value changes."""
    import shutil
    import subprocess

    assert shutil.which("vcd2fst"), "gtkwave is not installed (make setup installs it)"
    (tmp_path / "scope.vcd").write_text(vcd)
    subprocess.run(["vcd2fst", str(tmp_path / "scope.vcd"), str(tmp_path / "scope.fst")], check=True,
                   capture_output=True, timeout=60)
    back = subprocess.run(["fst2vcd", str(tmp_path / "scope.fst")], check=True, capture_output=True, text=True,
                          timeout=60).stdout
    declared = {line.split()[4]: line.split()[1:3] for line in back.splitlines() if line.startswith("$var")}
    assert declared == {"position.value": ["wire", "16"], "drive": ["wire", "16"], "Cylinder.active": ["wire", "5"],
                        "Cylinder.fired": ["wire", "8"]}  # the transition's id, not one bit per transition
    assert sorted(declared) == sorted(names)
    body = vcd.split("$enddefinitions $end\n", 1)[1].splitlines()
    assert body[0] == f"#{round(first_ms * 1000)}" and body[1] == "$dumpvars"  # the CSV's first time, in us
    assert sum(1 for line in body if line.startswith("b")) > len(names)  # the values changed after the first


def halt_at_extending_by_a_click(browser, server, where: str = EXTENDING_AT):
    """Click Extending, halt there; `where`: its file:line as the map has it."""
    browser.click("step:Cylinder.Extending")
    wait_for(lambda: "bp" in browser.js("return document.getElementById('step:Cylinder.Extending')"
                                        ".getAttribute('class')"), 10, "the breakpoint drawn on Extending")
    bps = server.state(10**9)["link"]["breakpoints"]
    assert [b["at"] for b in bps] == ["step Cylinder.Extending"], bps
    last = wait_for(lambda: (s := browser.last()) and s["halted"] and s, 20, "the halt at Extending")
    assert last["why"] == "breakpoint" and last["location"] == where, last
    wait_for(lambda: where in (browser.text("#halt-at") or ""), 10, "the halt's file:line on the page")
    line = where.rsplit(":", 1)[1]
    assert browser.text(".src-line.halted-line .ln") == line
    assert browser.text(".src-line.halted-line").strip() == f"{line}    step Extending {{"
    assert "step:Cylinder.Extending" in browser.active_steps()
    wait_for(lambda: browser.text("#bp-list") == "step Cylinder.Extending (hit 1) ✕", 10, "the breakpoints' list")
    # the guards on the halted snapshot: start_cmd holds (Retracted -> Extending), `not start_cmd` does not
    guard = "return document.getElementById(arguments[0]).querySelector('text.el-value').textContent"
    assert (browser.js(guard, "transition:Cylinder.0"), browser.js(guard, "transition:Cylinder.3")) == \
        ("✓ true", "✗ false")
    # the transition that took the chart there is marked as the one fired last (Cylinder.fired), and in the legend
    fired = "return [...document.querySelectorAll('#diagram g.fired')].map(g => g.id)"
    assert wait_for(lambda: browser.js(fired), 10, "the fired transition marked") == ["transition:Cylinder.0"]
    assert "fired last" in browser.text("#legend")
    return last


@pytest.mark.realtime
def test_the_page_follows_breaks_and_steps_pneumatic_cylinder_on_the_host_board(builds, firmware, online, browser,
                                                                                tmp_path):
    fw = firmware(builds["pneumatic_cylinder"], "--stimulus", str(slow_cycle(tmp_path)), fast=False)  # halted
    server = online(fw.map_path, str(fw.link))
    open_page(browser, server)
    assert browser.last()["halted"] and browser.text("#run-state").startswith("halted")
    browser.button("#run")
    seen, edges = follow_the_cycle(browser, 15, with_edges=True)
    assert seen[:len(CYCLE)] == CYCLE, seen
    for edge, values, least in zip(EDGES, edges, (3, 2)):  # the position ramps up, the PID follows it (and saturates)
        assert len(values - {None, ""}) >= least, (edge, values)
    assert browser.last()["consistency"] == "instant"  # a running target: one transaction per refresh

    before = halt_at_extending_by_a_click(browser, server)
    # docs/online.md's picture: zoomed in on the chart and PositionControl
    for _ in range(3):
        browser.button("#zoom-in")
    browser.js("const pane = document.getElementById('diagram'), p = pane.getBoundingClientRect();"
               "const r = document.getElementById('step:Cylinder.Retracted').getBoundingClientRect();"
               "pane.scrollBy(r.left - p.left - 10, r.top - p.top - 30);")
    wait_for(lambda: browser.js("return document.querySelector('#diagram g[id^=\"edge:PositionControl\"] "
                                "text.el-value').textContent") != "", 10, "PositionControl's values in sight")
    time.sleep(0.3)
    SCREENSHOT.parent.mkdir(parents=True, exist_ok=True)
    browser.driver.save_screenshot(str(SCREENSHOT))
    browser.button("#zoom-fit")
    browser.button("button.step[data-unit='instant']")
    after = wait_for(lambda: (s := browser.last()) and s["halted"] and s["why"] == "step" and s, 10, "the step")
    assert after["tick"] == before["tick"] + 1 and after["at"] == "instant", after

    # the scope: chosen items over logical time, exported as CSV and VCD
    plotted = ["position.value", "drive", "Cylinder.active", "Cylinder.fired"]
    for name in plotted:
        browser.js("document.getElementById('scope-item').value = arguments[0]", str(
            next(it["id"] for it in server.model()["items"] if it["name"] == name)))
        browser.button("#scope-add")
    browser.button("#clear-bps")
    browser.button("#run")
    csv = wait_for(lambda: (text := browser.js("return window.easylabOnline.csv()")).count("\n") > 10 and text,
                   15, "ten points in the scope")
    rows = [line.split(",") for line in csv.splitlines()]
    assert rows[0] == ["ms", *plotted]
    times = [float(r[0]) for r in rows[1:]]
    assert times == sorted(times) and times[0] >= after["ms"], times[:5]
    check_vcd(browser.js("return window.easylabOnline.vcd()"), plotted, times[0], tmp_path)

    # only what is in sight is polled: zoomed in on the top left corner, the
    # vars and params are out of sight and out of the snapshots (the scope's item stays)
    everything = set(browser.last()["values"])
    for _ in range(8):
        browser.button("#zoom-in")
    browser.js("document.getElementById('diagram').scrollTo(0, 0)")
    kp = str(next(it["id"] for it in server.model()["items"] if it["name"] == "kp"))
    assert kp in everything
    polled = wait_for(lambda: kp not in (v := set(browser.last()["values"])) and v, 10, "a smaller view")
    assert polled < everything
    assert set(map(str, browser.js("return window.easylabOnline.scope.ids"))) <= polled
    browser.button("#zoom-fit")

    # write once, through the form; reset into a halt
    browser.js("document.getElementById('write-item').value = 'kp'; document.getElementById('write-value').value = '-5'")
    browser.button("#write-form button[type='submit']")
    wait_for(lambda: "outside its range" in browser.text("#msg"), 10, "the range refusal")
    assert [e["message"].split(" - ")[0].rsplit("/", 1)[1] for e in browser.console_errors()] == ["write"]  # its 400
    browser.js("document.getElementById('write-value').value = '555'")
    browser.button("#write-form button[type='submit']")
    wait_for(lambda: browser.js("return document.getElementById('param:kp').querySelector('text.el-value')"
                                ".textContent") == "= 555", 10, "the written kp on the diagram")
    browser.button("#reset")
    wait_for(lambda: (s := browser.last()) and s["halted"] and s["why"] == "start" and s["tick"] == 0, 20,
             "the reset into a halt")
    wait_for(lambda: browser.active_steps() == [], 10, "no active step before the first evolution")
    assert browser.console_errors() == []


@pytest.mark.realtime
@pytest.mark.parametrize("board", ["avr", "pic18", "interp"], indirect=True)
def test_the_page_highlights_and_breaks_on_the_mcus_and_in_local_execution(board, builds, firmware, online, browser,
                                                                          tmp_path):
    fw = firmware(builds["pneumatic_cylinder"], "--stimulus", str(slow_cycle(tmp_path)), fast=False)
    server = online(fw.map_path, str(fw.link), model=None)  # the model the map names (the PIC18's variant)
    open_page(browser, server)
    browser.button("#run")
    seen, _ = follow_the_cycle(browser, 30, with_edges=False)
    assert has_cycle(seen), seen
    extending = next(s for s in fw.map.charts[0]["steps"] if s["name"] == "Extending")
    halt_at_extending_by_a_click(browser, server, extending["location"])
    assert browser.console_errors() == []



@pytest.mark.realtime
def test_the_page_highlights_and_breaks_in_remote_execution(build_cache, online, browser, tmp_path):
    """`easylab remote --debug tcp:PORT`: the application on this machine,
    its devices on a host-board proxy reading the slow cycle's sensors; the
    page reaches the debug interface as `tcp:127.0.0.1:PORT`. The chart's
    task runs every 25 ms here (the example's 5 ms leaves a proxy behind its
    clock on a loaded 2-core machine, and remote execution ends then)."""
    import subprocess
    import sys
    sys.path.insert(0, str(ROOT / "tests" / "remote"))
    from remote_testlib import EASYLAB, Proxy, device_columns, free_port, proxy_of
    from onlinelib import MODEL

    model = tmp_path / "pneumatic_cylinder.elab"
    model.write_text(MODEL.read_text().replace("task control period 5 ms", "task control period 25 ms"))
    stimulus = slow_cycle(tmp_path)
    proxy = Proxy(proxy_of(build_cache, model), tmp_path / "link", "--stimulus",
                  str(device_columns(stimulus, model, tmp_path / "devices.csv")))
    port, maps = free_port(), tmp_path / "maps"
    host = subprocess.Popen([*EASYLAB, "remote", str(model), "--target", str(proxy.link), "--stimulus", str(stimulus),
                             "--debug", f"tcp:{port}", "--maps", str(maps)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL, cwd=ROOT)
    try:
        wait_for(lambda: (maps / "debug_map.json").exists() or host.poll() is not None, 180, "the maps")
        assert host.poll() is None, host.communicate()
        server = online(maps / "debug_map.json", f"tcp:127.0.0.1:{port}", model=model)
        open_page(browser, server)
        seen, _ = follow_the_cycle(browser, 20, with_edges=False)
        assert has_cycle(seen), (seen, host.poll())
        # the task status: remote execution's overrun counters in the header
        assert "remote.control.overruns" in browser.text("#counts")
        dmap = DebugMap.load(maps / "debug_map.json")
        extending = next(s for s in dmap.charts[0]["steps"] if s["name"] == "Extending")
        halt_at_extending_by_a_click(browser, server, extending["location"])
        assert browser.console_errors() == []
    finally:
        host.kill()
        host.communicate()
        proxy.kill()
