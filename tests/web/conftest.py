"""Fixtures of the service panel's tests (tests/web): a host build of
examples/pt100_sensor.elab serving Modbus TCP, panels (`easylab-service web`
processes), and one headless Chromium for the whole session.

The firmware processes and builds are those of tests/service (svc_testlib).
"""

from __future__ import annotations

import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "service"))

from svc_testlib import EXAMPLES, build_model  # noqa: E402
from weblib import Browser, Panel, Pt100Devices, ramp_stimulus, start_browser, wait_for  # noqa: E402


def pt100_with_tcp(directory: Path) -> Path:
    """examples/pt100_sensor.elab with a Modbus TCP interface added (the
    example serves RTU only; the host board serves TCP for models that have it)."""
    directory.mkdir(parents=True, exist_ok=True)
    model = directory / "pt100_sensor.elab"
    model.write_text((EXAMPLES / "pt100_sensor.elab").read_text() + "modbus  tcp port 1502\n")
    return model


@pytest.fixture(scope="session")
def pt100_tcp(tmp_path_factory):
    """The host firmware of pt100_sensor with Modbus TCP (built once)."""
    d = tmp_path_factory.mktemp("pt100_tcp")
    return build_model(pt100_with_tcp(d / "model"), d / "host")


@pytest.fixture(scope="session")
def stimulus(tmp_path_factory) -> Path:
    return ramp_stimulus(tmp_path_factory.mktemp("stimulus") / "ramp.csv")


@pytest.fixture(scope="session")
def browser(tmp_path_factory):
    """One headless Chromium (a phone-sized window) for every test."""
    b = start_browser(tmp_path_factory, Browser)
    yield b
    b.quit()


@pytest.fixture
def panel(tmp_path):
    """Start panels (`easylab-service web`); each is stopped (and checked) at the end."""
    started: list[Panel] = []

    def start(smap: Path, *device_args: str, **kw) -> Panel:
        p = Panel(smap, list(device_args), **kw).start()
        started.append(p)
        return p
    yield start
    for p in started:
        p.stop()


@pytest.fixture(scope="module")
def bench(tmp_path_factory, pt100_tcp, stimulus, browser):
    """One pt100_sensor device (host board, Modbus TCP, ramp stimulus), its
    panel and the page open in the browser, for a module's tests."""
    work = tmp_path_factory.mktemp("panel")
    devices = Pt100Devices(pt100_tcp.exe, stimulus, work)
    fw = devices.start()
    panel = Panel(pt100_tcp.map, ["--tcp", f"127.0.0.1:{fw.port}"]).start()
    browser.get(panel.url)
    browser.console()  # what earlier pages of the session logged
    wait_for(lambda: browser.text("#link-state") == "connected", what="the page to say connected")
    b = SimpleNamespace(panel=panel, browser=browser, devices=devices, fw=fw, map=pt100_tcp.map, work=work)
    yield b
    panel.stop()
    devices.stop_all()
