"""The service panel's safety: the token off loopback, the Host rule on
loopback, writes from other origins refused (in a real browser too), no
blocking on a device that stops answering, and a bounded queue of work for
the device under a burst of requests."""

from __future__ import annotations

import signal
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from decimal import Decimal
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest

from weblib import Pt100Devices, http, wait_for


@pytest.fixture(scope="module")
def rig(tmp_path_factory, pt100_tcp, stimulus):
    """One running pt100_sensor for the module."""
    devices = Pt100Devices(pt100_tcp.exe, stimulus, tmp_path_factory.mktemp("safety"))
    fw = devices.start()
    yield fw
    devices.stop_all()


@pytest.fixture
def device_args(rig):
    return ["--tcp", f"127.0.0.1:{rig.port}"]


def degc(stored: int) -> str:
    """cal_offset's engineering text (unit "degC" scale 0.1) of a stored value."""
    return str(Decimal(stored).scaleb(-1))


def cal_offset(rig) -> int:
    from easylab.host_tools.modbus_link import ModbusLink
    link = ModbusLink.tcp("127.0.0.1", rig.port, 1, 2.0)
    try:
        return link.read("holding", 1, 1)[0]
    finally:
        link.close()


def connected(panel) -> bool:
    return panel.link()["state"] == "connected"


# ---------------------------------------------------------------- the token


def test_off_loopback_nothing_is_read_or_written_without_the_token(pt100_tcp, rig, device_args, panel):
    p = panel(pt100_tcp.map, *device_args, listen="0.0.0.0:0")
    assert p.url.startswith(f"http://0.0.0.0:{p.port}/?token=") and len(p.token) >= 20
    wait_for(lambda: f"the token {p.token}" in "".join(p.out), what="the token's line")
    wait_for(lambda: connected(p), what="the panel to connect")
    before = cal_offset(rig)
    for path in ("/", "/static/panel.js", "/static/vendor/uPlot.iife.min.js", "/api/map", "/api/samples",
                 "/api/backup"):
        for headers in ({}, {"Authorization": "Bearer wrong-token-123"}, {"Cookie": f"easylab_panel_{p.port}=x"}):
            r = http("GET", p.base + path, headers=headers)
            assert r.status == 401, (path, headers, r.status)
            assert "needs its token" in r.text and "cal_offset" not in r.text
    assert http("GET", f"{p.base}/?token=wrong-token-123").status == 401
    # A write with everything but the token.
    r = http("POST", p.base + "/api/write", {"name": "cal_offset", "value": "33"},
             headers={"Origin": p.base, "X-EasyLab-CSRF": "anything"})
    assert r.status == 401
    assert cal_offset(rig) == before
    # With the token: as a bearer, or as the cookie the token address sets.
    assert p.api("GET", "/api/map").status == 200
    r = http("GET", f"{p.base}/?token={p.token}")
    assert r.status == 303 and r.headers["Location"] == "/"
    cookie = r.headers["Set-Cookie"]
    assert cookie.startswith(f"easylab_panel_{p.port}={p.token};")
    assert "HttpOnly" in cookie and "SameSite=Strict" in cookie
    r = http("GET", p.base + "/api/map", headers={"Cookie": f"easylab_panel_{p.port}={p.token}"})
    assert r.status == 200 and r.json()["model"] == "pt100_sensor"
    r = p.api("POST", "/api/write", {"name": "cal_offset", "value": "3.3"})  # degC: stored in tenths
    assert r.status == 200 and r.json()["value"] == 33 and r.json()["text"] == "3.3"
    assert cal_offset(rig) == 33
    p.api("POST", "/api/write", {"name": "cal_offset", "value": degc(before)})


def test_the_token_address_opens_the_page_in_a_browser(pt100_tcp, device_args, panel, browser):
    p = panel(pt100_tcp.map, *device_args, listen="0.0.0.0:0")
    browser.get(p.base + "/")
    assert "needs its token" in browser.text("body")
    browser.get(f"{p.base}/?token={p.token}")
    wait_for(lambda: browser.text("#link-state") == "connected", what="the page to connect")
    assert browser.driver.current_url == p.base + "/"                     # the token left the address bar
    assert f"easylab_panel_{p.port}" not in browser.js("return document.cookie")   # HttpOnly


def test_a_given_token_is_required_on_loopback_too(pt100_tcp, device_args, panel):
    p = panel(pt100_tcp.map, *device_args, token="bench-token-42")
    assert p.token == "bench-token-42"
    assert http("GET", p.base + "/api/samples").status == 401
    assert p.api("GET", "/api/samples").status == 200


def test_loopback_panel_answers_loopback_names_only(pt100_tcp, device_args, panel):
    p = panel(pt100_tcp.map, *device_args)
    assert p.token is None and p.url == f"http://127.0.0.1:{p.port}/"
    for host in (f"127.0.0.1:{p.port}", f"localhost:{p.port}", "127.0.0.1"):
        assert http("GET", p.base + "/api/map", headers={"Host": host}).status == 200, host
    # A name that resolves to this machine from outside (DNS rebinding) is refused.
    for host in (f"panel.example.com:{p.port}", f"10.1.2.3:{p.port}"):
        r = http("GET", p.base + "/api/map", headers={"Host": host})
        assert r.status == 403 and "only to a loopback address" in r.json()["error"], host


# ---------------------------------------------------------------- other origins


def test_writes_must_be_same_origin_json_with_the_csrf_header(pt100_tcp, rig, device_args, panel):
    p = panel(pt100_tcp.map, *device_args)
    wait_for(lambda: connected(p), what="the panel to connect")
    before = cal_offset(rig)
    body = {"name": "cal_offset", "value": "4.4"}
    refused = {
        "another origin": {"Origin": "http://evil.example", p.csrf_header: p.csrf},
        "another port": {"Origin": f"http://127.0.0.1:{p.port + 1}", p.csrf_header: p.csrf},
        "a null origin": {"Origin": "null", p.csrf_header: p.csrf},
        "a cross-site fetch": {"Sec-Fetch-Site": "cross-site", p.csrf_header: p.csrf},
        "no CSRF header": {"Origin": p.base},
        "a wrong CSRF header": {"Origin": p.base, p.csrf_header: "guess"},
    }
    for what, headers in refused.items():
        r = http("POST", p.base + "/api/write", body, headers=headers)
        assert r.status == 403 and r.json()["error"].startswith("refused: "), (what, r.status, r.text)
    r = http("POST", p.base + "/api/write", b'{"name": "cal_offset", "value": "44"}',
             headers={"Content-Type": "text/plain", "Origin": p.base, p.csrf_header: p.csrf})
    assert r.status == 403 and "not JSON" in r.json()["error"]
    assert cal_offset(rig) == before
    r = p.api("POST", "/api/write", body)                       # the page's own request
    assert r.status == 200 and cal_offset(rig) == 44
    p.api("POST", "/api/write", {"name": "cal_offset", "value": degc(before)})


ATTACK = """<!doctype html><title>elsewhere</title>
<iframe name="sink"></iframe>
<form id="f" method="POST" action="PANEL/api/write" enctype="text/plain" target="sink">
<input name='{"name":"cal_offset","value":"73","pad":"' value='"}'></form>
<script>
const results = {};
async function attack() {
  try {   // a simple request: no preflight, the cookies go along
    await fetch("PANEL/api/write", {method: "POST", mode: "no-cors", credentials: "include",
      headers: {"Content-Type": "text/plain"}, body: JSON.stringify({name: "cal_offset", value: "71"})});
    results.simple = "sent";
  } catch (e) { results.simple = "blocked"; }
  try {   // JSON with a guessed header needs a preflight, which the panel does not grant
    const r = await fetch("PANEL/api/write", {method: "POST", credentials: "include",
      headers: {"Content-Type": "application/json", "X-EasyLab-CSRF": "guess"},
      body: JSON.stringify({name: "cal_offset", value: "72"})});
    results.json = "status " + r.status;
  } catch (e) { results.json = "blocked"; }
  try {   // reading the page's map, to learn its CSRF token
    const r = await fetch("PANEL/api/map", {credentials: "include"});
    results.read = await r.text();
  } catch (e) { results.read = "blocked"; }
  document.getElementById("f").submit();
  results.form = "sent";
  window.attackDone = results;
}
attack();
</script>"""


class _AttackPage(BaseHTTPRequestHandler):
    page = b""

    def do_GET(self):
        self.send_response(200)
        self.send_header("Content-Type", "text/html")
        self.end_headers()
        self.wfile.write(self.page)

    def log_message(self, *args):
        pass


@pytest.mark.parametrize("with_token", [False, True], ids=["loopback", "token"])
def test_a_page_from_another_origin_cannot_write(with_token, pt100_tcp, rig, device_args, panel, browser):
    p = panel(pt100_tcp.map, *device_args, **({"token": "cookie-token-77"} if with_token else {}))
    # The browser has the panel open (and, with a token, holds its cookie).
    browser.get(p.url)
    wait_for(lambda: browser.text("#link-state") == "connected", what="the panel page")
    before = cal_offset(rig)
    _AttackPage.page = ATTACK.replace("PANEL", p.base).encode()
    server = ThreadingHTTPServer(("127.0.0.1", 0), _AttackPage)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        browser.get(f"http://127.0.0.1:{server.server_address[1]}/")
        results = wait_for(lambda: browser.js("return window.attackDone"), what="the other page's attempts")
        assert results["json"] == "blocked" and results["read"] == "blocked"
        # Each attempt reached the panel and was refused there as cross-origin:
        # the simple fetch, the form, and the JSON fetch's preflight (which
        # carries no cookie: with a token it is refused earlier, as unknown).
        wait_for(lambda: sum("refused a request from another origin" in line for line in p.err) >= 3 - with_token,
                 what=f"the panel's refusals ({p.err})")
        time.sleep(0.3)  # the form's request has been answered; give a wrongly accepted write time to land
        assert cal_offset(rig) == before
    finally:
        server.shutdown()
        server.server_close()


# ---------------------------------------------------------------- a device that stops answering


def timed(fn):
    t0 = time.monotonic()
    result = fn()
    return result, time.monotonic() - t0


def test_a_stalled_device_never_blocks_the_server(pt100_tcp, rig, device_args, panel):
    p = panel(pt100_tcp.map, *device_args, timeout=0.5)
    wait_for(lambda: connected(p), what="the panel to connect")
    rig.proc.send_signal(signal.SIGSTOP)            # connected, and silent
    try:
        slowest = 0.0
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            r, took = timed(lambda: p.api("GET", "/api/samples?after=1000000000"))
            slowest = max(slowest, took)
            if r.json()["link"]["state"] == "lost":
                break
            time.sleep(0.05)
        link = r.json()["link"]
        assert link["state"] == "lost", link
        assert f"no reply from 127.0.0.1:{rig.port} within 0.5 s" in link["message"]
        assert link["stats"]["timeouts"] >= 1
        assert slowest < 0.5, slowest                  # reads never wait for the device
        r, took = timed(lambda: p.api("POST", "/api/write", {"name": "cal_offset", "value": "5"}))
        assert r.status == 503 and "not connected" in r.json()["error"] and took < 0.5
        r, took = timed(lambda: p.api("GET", "/api/backup"))
        assert r.status == 503 and took < 0.5
    finally:
        rig.proc.send_signal(signal.SIGCONT)
    wait_for(lambda: connected(p), timeout=15, what="the panel to reconnect")
    assert p.api("POST", "/api/write", {"name": "cal_offset", "value": "0"}).status == 200


def test_a_burst_of_writes_queues_a_bounded_amount_of_work(pt100_tcp, rig, device_args, panel):
    p = panel(pt100_tcp.map, *device_args, timeout=2.0)
    wait_for(lambda: connected(p), what="the panel to connect")
    p.csrf  # noqa: B018 - fetch the token before the burst
    burst = 40
    start = threading.Barrier(burst)

    def write(k: int):
        start.wait()
        t0 = time.monotonic()
        r = p.api("POST", "/api/write", {"name": "cal_gain", "value": str(1000 + k)})
        return r.status, time.monotonic() - t0
    # The device stalls: whatever is queued now waits, the rest must be refused at once.
    rig.proc.send_signal(signal.SIGSTOP)
    try:
        with ThreadPoolExecutor(burst) as pool:
            answers = list(pool.map(write, range(burst)))
    finally:
        rig.proc.send_signal(signal.SIGCONT)
    statuses = [s for s, _ in answers]
    busy = [took for s, took in answers if s == 429]
    assert set(statuses) <= {429, 503, 200}, statuses
    assert len(statuses) - len(busy) <= 5, statuses    # a queue of 4, and one running
    assert busy and max(busy) < 1.0, busy               # refused without waiting for the device
    assert max(took for _, took in answers) < 12
    wait_for(lambda: connected(p), timeout=15, what="the panel to reconnect")
    # On a live device, every answered write is two requests, a refused one none.
    before = p.link()["stats"]["requests"]
    seq0 = p.api("GET", "/api/samples?after=-1").json()["samples"][-1]["seq"]
    with ThreadPoolExecutor(20) as pool:
        statuses = list(pool.map(lambda k: p.api("POST", "/api/write", {"name": "cal_gain", "value": "1000"}).status,
                                 range(20)))
    after = p.link()["stats"]["requests"]
    seq1 = p.api("GET", "/api/samples?after=-1").json()["samples"][-1]["seq"]
    written = statuses.count(200)
    assert written >= 1 and set(statuses) <= {200, 429}
    assert abs((after - before) - (2 * written + 3 * (seq1 - seq0))) <= 6
