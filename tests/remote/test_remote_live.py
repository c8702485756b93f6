"""Live change in remote execution: an application edit swaps in while the
proxy keeps running; an edit of the device model is refused."""

from __future__ import annotations

import signal
import subprocess
import time

from remote_testlib import EASYLAB, EXAMPLES, Proxy, device_columns, proxy_of, wait_for


def wait_for_text(path, text: str, timeout: float = 20.0) -> None:
    deadline = time.monotonic() + timeout
    while text not in path.read_text():
        assert time.monotonic() < deadline, f"{text!r} not in {path.read_text()!r}"
        time.sleep(0.02)


def test_application_edits_swap_in_device_edits_are_refused(build_cache, tmp_path):
    original = EXAMPLES / "pt100_sensor.elab"
    model = tmp_path / "pt100_sensor.elab"
    model.write_text(original.read_text())
    devices = device_columns(EXAMPLES / "pt100_sensor.stimulus.csv", original, tmp_path / "devices.csv")
    proxy = Proxy(proxy_of(build_cache, original), tmp_path / "link", "--fast", "--stimulus", str(devices))
    trace, log = tmp_path / "remote.csv", tmp_path / "remote.log"
    try:
        with log.open("w") as err:
            # Lock-step virtual time (the proxy waits while the host checks an
            # edit): long enough to edit twice, ended by SIGINT.
            host = subprocess.Popen([*EASYLAB, "remote", str(model), "--target", str(proxy.link), "--watch",
                                     "--fast", "--duration", "1h", "--trace", str(trace)], stderr=err,
                                    stdout=subprocess.DEVNULL, stdin=subprocess.DEVNULL, text=True)
            wait_for(trace)
            time.sleep(0.3)  # the watcher has taken its first look at the files
            model.write_text(original.read_text().replace("alarm_high: int16 = 800", "alarm_high: int16 = 700"))
            wait_for_text(log, "the program id changed")
            model.write_text(original.read_text().replace("Pt100(channel = 0)", "Pt100(channel = 1)"))
            wait_for_text(log, "the proxy must be rebuilt and flashed")
            host.send_signal(signal.SIGINT)  # the run ends at the next instant, the trace complete
            assert host.wait(timeout=60) == 0, log.read_text()
        assert "changes the device model (devices sensor.adc)" in log.read_text()
        assert proxy.finish()[0] == 0  # it ran until the host's STOP
    finally:
        proxy.kill()
