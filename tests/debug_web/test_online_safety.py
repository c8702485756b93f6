"""The online mode's safety (docs/online.md, "Safety"): loopback by default
and loopback Host names only, a token on any other address, changes
refused from another origin or without the page's CSRF header, a dead or
silent target never blocks the server, reconnection by itself (and a
firmware with another program refused by its id)."""

from __future__ import annotations

import socket
import threading
import time

from debug_testlib import builds, firmware  # noqa: F401 (fixtures)
from onlinelib import http, wait_for


def value_of(server, name: str):
    """An item's value in a snapshot taken from now on (the item is put in view first)."""
    item = next(it for it in server.model()["items"] if it["name"] == name)
    assert server.api("POST", "/api/view", {"items": [item["id"]]}).status == 200
    seen = server.state()["snapshots"]
    after = seen[-1]["seq"] if seen else -1
    snap = wait_for(lambda: [s for s in server.state(after)["snapshots"] if str(item["id"]) in s["values"]], 10,
                    f"a snapshot with {name}")[-1]
    return snap["values"][str(item["id"])]


def test_loopback_by_default_answers_loopback_host_names_only(builds, firmware, online):
    fw = firmware(builds["pneumatic_cylinder"])
    server = online(fw.map_path, str(fw.link), listen="127.0.0.1:0")
    assert server.token is None and server.url.startswith("http://127.0.0.1:")
    for host in (f"127.0.0.1:{server.port}", f"localhost:{server.port}"):
        assert http("GET", server.base + "/api/model", headers={"Host": host}).status == 200
    for host in ("evil.example", f"evil.example:{server.port}", f"192.168.1.5:{server.port}"):
        r = http("GET", server.base + "/api/model", headers={"Host": host})
        assert r.status == 403 and "loopback" in r.json()["error"], host


def test_off_loopback_everything_needs_the_token(builds, firmware, online):
    fw = firmware(builds["pneumatic_cylinder"])
    server = online(fw.map_path, str(fw.link), listen="0.0.0.0:0")
    assert server.token and "token=" in server.url
    for method, path, body in (("GET", "/", None), ("GET", "/api/model", None), ("GET", "/api/state", None),
                               ("POST", "/api/write", {"name": "start_cmd", "value": "1"}),
                               ("POST", "/api/command", {"command": "run"})):
        r = http(method, server.base + path, body, headers={"Origin": server.base})
        assert r.status == 401, (method, path, r.status)
    assert http("GET", server.base + "/api/model", headers={"Authorization": "Bearer wrong-token"}).status == 401
    assert server.api("GET", "/api/model").status == 200
    assert value_of(server, "start_cmd") is False  # the refused write did not happen
    # the printed address sets a cookie and leaves the token out of the address bar
    r = http("GET", f"{server.base}/?token={server.token}")
    assert r.status == 303 and r.headers["Location"] == "/" and server.token in r.headers["Set-Cookie"]


def test_changes_are_refused_from_another_origin_or_without_the_csrf_header(builds, firmware, online):
    fw = firmware(builds["pneumatic_cylinder"])  # halted at its first instant: a write applies at once
    server = online(fw.map_path, str(fw.link))
    csrf = {server.model()["csrf_header"]: server.model()["csrf"]}
    write = {"name": "target", "value": "123"}
    refused = [
        ({**csrf, "Origin": "http://evil.example"}, write),  # another origin
        ({**csrf, "Sec-Fetch-Site": "cross-site"}, write),  # a cross-site request without Origin
        ({"Origin": server.base}, write),  # no CSRF header
        ({**csrf, "Origin": server.base, "Content-Type": "text/plain"}, write),  # a form's body
    ]
    for headers, body in refused:
        r = http("POST", server.base + "/api/write", body, headers=headers)
        assert r.status == 403 and r.json()["error"].startswith("refused"), (headers, r.status)
    r = http("POST", server.base + "/api/command", {"command": "run"}, headers={**csrf, "Origin": "http://x.example"})
    assert r.status == 403
    assert value_of(server, "target") == 900
    r = server.api("POST", "/api/write", write)
    assert r.status == 200 and r.json() == {"name": "target", "value": 123, "applied": True}
    assert value_of(server, "target") == 123
    # bad requests are refused by name, before the target is asked
    for body, words in (({"name": "valve.duty", "value": "1"}, "read-only"), ({"name": "target", "value": "5000"},
                        "outside its range"), ({"name": "nothing", "value": "1"}, "no item")):
        r = server.api("POST", "/api/write", body)
        assert r.status == 400 and words in r.json()["error"], (body, r.json())
    assert server.api("POST", "/api/breakpoint", {"element": "var:drive"}).status == 400
    assert server.api("POST", "/api/command", {"command": "step", "unit": "forever"}).status == 400


def test_a_dead_target_never_blocks_the_server_and_it_reconnects_by_itself(builds, firmware, online, tmp_path):
    exe = builds["pneumatic_cylinder"]
    link = tmp_path / f"{exe.name}.pty"  # where the firmware will open its link
    server = online(exe.parent / "debug_map.json", str(link))
    started = time.monotonic()
    state = server.state()
    assert time.monotonic() - started < 2 and state["link"]["state"] == "connecting", state["link"]
    r = server.api("POST", "/api/command", {"command": "break"})
    assert r.status == 503 and "not connected" in r.json()["error"]
    fw = firmware(exe, halt=False)
    wait_for(lambda: server.state(10**9)["link"]["state"] == "connected", 20, "the connection")
    fw.stop()
    wait_for(lambda: server.state(10**9)["link"]["state"] == "lost", 20, "the lost connection")
    started = time.monotonic()
    assert server.api("GET", "/api/model").status == 200 and time.monotonic() - started < 2
    firmware(exe, halt=False)
    link_state = wait_for(lambda: (s := server.state(10**9)["link"])["state"] == "connected" and s, 20, "reconnection")
    assert link_state["connects"] == 2 and "again" in link_state["message"]


def test_a_silent_target_never_blocks_the_server(builds, online):
    """A target that accepts the connection and never answers: the page's
    reads answer at once, a command fails within its time limit."""
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(4)
    accepted = []
    stop = threading.Event()

    def accept():
        listener.settimeout(0.2)
        while not stop.is_set():
            try:
                accepted.append(listener.accept()[0])
            except OSError:
                pass
    threading.Thread(target=accept, daemon=True).start()
    try:
        exe = builds["pneumatic_cylinder"]
        server = online(exe.parent / "debug_map.json", f"tcp:127.0.0.1:{listener.getsockname()[1]}")
        wait_for(lambda: accepted, 10, "the server's connection")
        for _ in range(5):
            started = time.monotonic()
            link = server.state()["link"]
            assert time.monotonic() - started < 1.0 and link["state"] != "connected", link
            time.sleep(0.2)
    finally:
        stop.set()
        listener.close()
        for s in accepted:
            s.close()


def test_a_firmware_of_another_program_is_refused_by_its_id(builds, firmware, online):
    fw = firmware(builds["blink"])
    server = online(builds["pneumatic_cylinder"].parent / "debug_map.json", str(fw.link))
    link = wait_for(lambda: (s := server.state()["link"])["state"] == "wrong program" and s, 20, "the refusal")
    assert "not the map's" in link["message"] and "pneumatic_cylinder" in link["message"]


# A page of another origin, open in the same browser as the online page,
# tries every way a page can reach the server.
OTHER_PAGE = """<!doctype html><title>elsewhere</title>
<iframe name="sink"></iframe>
<form id="f" method="POST" action="ONLINE/api/write" enctype="text/plain" target="sink">
<input name='{"name":"kp","value":"1234","pad":"' value='"}'></form>
<script>
const tried = {};
async function attempt() {
  try {   // a simple request: no preflight
    await fetch("ONLINE/api/command", {method: "POST", mode: "no-cors", credentials: "include",
      headers: {"Content-Type": "text/plain"}, body: JSON.stringify({command: "run"})});
    tried.simple = "sent";
  } catch (e) { tried.simple = "blocked"; }
  try {   // JSON with a guessed CSRF header: a preflight the server does not grant
    const r = await fetch("ONLINE/api/command", {method: "POST", credentials: "include",
      headers: {"Content-Type": "application/json", "X-EasyLab-CSRF": "guess"}, body: JSON.stringify({command: "run"})});
    tried.json = "status " + r.status;
  } catch (e) { tried.json = "blocked"; }
  try {   // reading the model, to learn the CSRF token
    const r = await fetch("ONLINE/api/model", {credentials: "include"});
    tried.read = await r.text();
  } catch (e) { tried.read = "blocked"; }
  document.getElementById("f").submit();
  window.tried = tried;
}
attempt();
</script>"""


def test_a_page_from_another_origin_can_neither_command_nor_write(builds, firmware, online, browser):
    from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

    fw = firmware(builds["pneumatic_cylinder"])  # halted at its first instant
    server = online(fw.map_path, str(fw.link))
    browser.get(server.url)  # the online page is open in the same browser
    wait_for(lambda: browser.last() is not None, 30, "the online page")
    page = OTHER_PAGE.replace("ONLINE", server.base).encode()

    class Elsewhere(BaseHTTPRequestHandler):
        def do_GET(self):
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.end_headers()
            self.wfile.write(page)

        def log_message(self, *args):
            pass
    other = ThreadingHTTPServer(("127.0.0.1", 0), Elsewhere)
    threading.Thread(target=other.serve_forever, daemon=True).start()
    try:
        browser.get(f"http://127.0.0.1:{other.server_address[1]}/")
        tried = wait_for(lambda: browser.js("return window.tried"), 20, "the other page's attempts")
        assert tried["json"] == "blocked" and tried["read"] == "blocked", tried
        # the simple request, the preflight and the form reached the server and were refused there
        wait_for(lambda: sum("refused a request from another origin" in line for line in server.err) >= 3, 10,
                 f"the server's refusals ({server.err})")
        time.sleep(0.3)  # a wrongly accepted request would have landed by now
        assert value_of(server, "kp") == 400
        assert server.state(10**9)["link"]["state"] == "connected"
        assert [s["halted"] for s in server.state()["snapshots"][-3:]] == [True] * 3  # `run` never reached it
    finally:
        other.shutdown()
        other.server_close()
        browser.get("about:blank")
        browser.console_errors()  # the other page's blocked requests
