"""Helpers of the service panel's tests: the panel process, plain HTTP
requests, headless Chromium, waiting for conditions."""

from __future__ import annotations

import json
import os
import queue
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
# Chromium on this machine: no first-run work, no background traffic (the
# machine's closed network refuses it), a fresh profile per session.
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--disable-dev-shm-usage"]
PHONE = {"width": 390, "height": 844, "pixelRatio": 1}


def wait_for(condition, timeout: float = 10.0, what: str = "the condition", every: float = 0.05):
    """Poll `condition` until it returns a true value (returned), or fail."""
    deadline = time.monotonic() + timeout
    last_error = None
    while True:
        try:
            value = condition()
            if value:
                return value
        except Exception as err:  # a page half-built, a process not listening yet
            last_error = err
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}"
                                 + (f" (last error: {last_error!r})" if last_error else ""))
        time.sleep(every)


def ramp_stimulus(path: Path, seconds: int = 600) -> Path:
    """A PT100 stimulus for a real-time run: the raw reading goes up and down
    by one every 200 ms between 276 and 286 (about 20..30 degC)."""
    rows = ["time_us,sensor.raw"]
    for k in range(seconds * 5):
        step = k % 20
        rows.append(f"{k * 200000},{276 + (step if step < 10 else 20 - step)}")
    path.write_text("\n".join(rows) + "\n")
    return path


class Pt100Devices:
    """pt100_sensor firmwares serving Modbus TCP in real time, on the ramp
    stimulus, with a trace each and one non-volatile store; a restart keeps
    the port."""

    def __init__(self, exe: Path, stimulus: Path, workdir: Path):
        self.exe = exe
        self.stimulus = stimulus
        self.workdir = workdir
        self.nvram = workdir / "nvram.bin"
        self.started = []

    def start(self, port: int | None = None, trace: str = "trace.csv"):
        from svc_testlib import Firmware
        fw = Firmware(self.exe, self.workdir, rtu=False, nvram=self.nvram, port=port,
                      extra=["--stimulus", str(self.stimulus), "--trace", str(self.workdir / trace)]).start()
        self.started.append(fw)
        return fw

    def stop_all(self) -> None:
        for fw in self.started:
            fw.stop()


# ---------------------------------------------------------------- HTTP


class Reply:
    def __init__(self, status: int, headers, body: bytes):
        self.status = status
        self.headers = headers
        self.body = body

    @property
    def text(self) -> str:
        return self.body.decode("utf-8", "replace")

    def json(self):
        return json.loads(self.body)


class _NoRedirect(urllib.request.HTTPRedirectHandler):
    def redirect_request(self, *args, **kw):
        return None


_OPENER = urllib.request.build_opener(_NoRedirect)


def http(method: str, url: str, body=None, headers: dict | None = None, timeout: float = 20.0) -> Reply:
    """One request over a real socket; HTTP errors are replies, not exceptions."""
    data = None
    headers = dict(headers or {})
    if body is not None:
        data = body if isinstance(body, bytes) else json.dumps(body).encode()
        headers.setdefault("Content-Type", "application/json")
    request = urllib.request.Request(url, data=data, method=method, headers=headers)
    try:
        with _OPENER.open(request, timeout=timeout) as r:
            return Reply(r.status, r.headers, r.read())
    except urllib.error.HTTPError as err:
        return Reply(err.code, err.headers, err.read())


# ---------------------------------------------------------------- the panel process


def start_browser(tmp_path_factory, browser_class):
    """A headless Chromium of ``browser_class`` in a folder of its own, once
    Debian's chromium and chromium-driver are there (`make setup`)."""
    missing = [tool for tool in ("chromium", "chromedriver") if shutil.which(tool) is None]
    assert not missing, f"{' and '.join(missing)} missing: `make setup` installs Debian's chromium and chromium-driver"
    return browser_class(tmp_path_factory.mktemp("chromium"))


class PageServer:
    """A page's server (`easylab-service ... web`, `easylab-debug web`) in a
    process, started with ``args``; `url` is the address it printed, `base`
    the same without the token, reached over 127.0.0.1 (it listens there in
    every test). ``what`` names it in failures; ``info`` is the API path of
    its document with the CSRF header's name and value."""

    what = "the server"
    info = "/api/map"
    start_timeout = 30.0

    def __init__(self, args: list[str], cwd: Path | None = None):
        self.args = args
        self.cwd = cwd
        self.proc = None
        self.out: list[str] = []
        self.err: list[str] = []
        self._lines: queue.Queue = queue.Queue()

    def start(self):
        env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
        self.proc = subprocess.Popen(self.args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                     stdin=subprocess.DEVNULL, env=env, cwd=self.cwd)
        for stream, sink in ((self.proc.stdout, self.out), (self.proc.stderr, self.err)):
            threading.Thread(target=self._read, args=(stream, sink), daemon=True).start()
        first = self._lines.get(timeout=self.start_timeout)
        if first is None:
            raise AssertionError(f"{self.what} exited {self.proc.wait()}: {''.join(self.err)}")
        m = re.search(r"(http://\S+)", first)
        assert m, first
        self.url = m.group(1)
        self.port = int(re.search(r":(\d+)/", self.url).group(1))
        self.token = (re.search(r"token=(\S+)", self.url) or [None, None])[1]
        self.base = f"http://127.0.0.1:{self.port}"
        return self

    def _read(self, stream, sink: list[str]) -> None:
        for line in stream:
            sink.append(line)
            if sink is self.out:
                self._lines.put(line)
        if sink is self.out:
            self._lines.put(None)

    def document(self) -> dict:
        """The server's own document (``info``), read once."""
        if not hasattr(self, "_document"):
            h = {"Authorization": f"Bearer {self.token}"} if self.token else {}
            self._document = http("GET", self.base + self.info, headers=h).json()
        return self._document

    @property
    def csrf(self) -> str:
        return self.document()["csrf"]

    @property
    def csrf_header(self) -> str:
        return self.document()["csrf_header"]

    def api(self, method: str, path: str, body=None, headers: dict | None = None) -> Reply:
        """A request as the page makes it (the token, if any, as a bearer)."""
        h = {"Authorization": f"Bearer {self.token}"} if self.token else {}
        if method == "POST":
            h[self.csrf_header] = self.csrf
            h["Origin"] = self.base
        h.update(headers or {})
        return http(method, self.base + path, body, h)

    def stop(self) -> None:
        """SIGTERM; the server must end by itself, with status 0 and no traceback."""
        if self.proc is None or self.proc.poll() is not None:
            return
        self.proc.send_signal(signal.SIGTERM)
        try:
            status = self.proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            raise AssertionError(f"{self.what} did not stop on SIGTERM")
        err = "".join(self.err)
        assert status == 0 and "Traceback" not in err, (status, err)


class Panel(PageServer):
    """`easylab-service --map MAP DEVICE... web --listen ... [--token T]`."""

    what = "the panel"

    def __init__(self, smap: Path, device_args: list[str], listen: str = "127.0.0.1:0", token: str | None = None,
                 timeout: float = 0.5, every: str = "100ms", extra: list[str] | None = None):
        args = [sys.executable, "-m", "easylab.host_tools.service_cli", "--map", str(smap), "--timeout",
                str(timeout), *device_args, "web", "--listen", listen, "--every", every]
        if token is not None:
            args += ["--token", token]
        super().__init__(args + (extra or []))

    def _map(self) -> dict:
        return self.document()

    def link(self) -> dict:
        return self.api("GET", "/api/samples?after=1000000000").json()["link"]

    def latest(self) -> dict:
        """The newest sample, by item name."""
        doc = self.api("GET", "/api/samples?after=-1").json()
        names = [it["name"] for it in self._map()["items"]]
        return dict(zip(names, doc["samples"][-1]["v"]))


# ---------------------------------------------------------------- the browser


class Browser:
    """Headless Chromium through chromedriver (selenium), phone-sized, with
    downloads going to `downloads`."""

    def __init__(self, workdir: Path):
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service

        self.downloads = workdir / "downloads"
        self.downloads.mkdir()
        opts = webdriver.ChromeOptions()
        opts.binary_location = "/usr/bin/chromium"
        for flag in CHROMIUM_FLAGS + [f"--user-data-dir={workdir / 'profile'}"]:
            opts.add_argument(flag)
        opts.add_experimental_option("mobileEmulation", {"deviceMetrics": PHONE})
        opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
        self.driver = webdriver.Chrome(options=opts, service=Service("/usr/bin/chromedriver"))
        self.driver.execute_cdp_cmd("Browser.setDownloadBehavior",
                                    {"behavior": "allow", "downloadPath": str(self.downloads)})

    def get(self, url: str) -> None:
        self.driver.get(url)

    def js(self, script: str, *args):
        return self.driver.execute_script(script, *args)

    def find(self, css: str):
        from selenium.webdriver.common.by import By
        return self.driver.find_element(By.CSS_SELECTOR, css)

    def text(self, css: str) -> str:
        return self.js("const e = document.querySelector(arguments[0]); return e ? e.textContent : null;", css)

    def console(self) -> list[dict]:
        """The browser's console and network errors since the last call."""
        return self.driver.get_log("browser")

    def screenshot(self, path: Path) -> None:
        """The whole page, phone-wide."""
        height = self.js("return document.documentElement.scrollHeight")
        self.driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                                    {"width": PHONE["width"], "height": height, "deviceScaleFactor": 1,
                                     "mobile": True})
        try:
            self.driver.save_screenshot(str(path))
        finally:
            self.driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                                        {"width": PHONE["width"], "height": PHONE["height"], "deviceScaleFactor": 1,
                                         "mobile": True})

    def quit(self) -> None:
        self.driver.quit()


# ---------------------------------------------------------------- the bench of the page tests


def device_values(bench, *names: str) -> dict:
    """Read items straight from the device with the project's Modbus link
    (pymodbus), not through the panel."""
    from easylab.host_tools.modbus_link import ModbusLink
    from easylab.host_tools.service_cli import read_values
    from easylab.host_tools.service_map import load_map

    smap = load_map(bench.map)
    link = ModbusLink.tcp("127.0.0.1", bench.fw.port, 1, 2.0)
    try:
        return read_values(link, [smap.item(n) for n in names])
    finally:
        link.close()


def item_text(bench, name: str, part: str = ".value") -> str:
    return bench.browser.text(f'[data-item="{name}"] {part}')


def set_in_page(bench, name: str, text: str) -> None:
    """Type a value into an item's field and press Set, as a person does."""
    field = bench.browser.find(f'[data-item="{name}"] input')
    field.clear()
    field.send_keys(text)
    bench.browser.find(f'[data-item="{name}"] button.set').click()
