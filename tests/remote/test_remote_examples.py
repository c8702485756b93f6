"""Acceptance: for every example and its stimulus (and the interpreter's
dataflow test model, for device ports with rates and float32 device data),
the host-board proxy with `easylab remote --fast` (lock-step virtual time)
writes the host-native firmware's trace, byte for byte; and so for a model
that declares a safe value."""

from __future__ import annotations

import pytest

from remote_testlib import EXAMPLES, Proxy, device_columns, native_of, proxy_of, remote, run_native

DATA = EXAMPLES.parent / "tests" / "interp" / "data"
SAFE = EXAMPLES.parent / "tests" / "remote" / "data"
CASES = {  # name: (model, stimulus or None, duration)
    **{name: (EXAMPLES / f"{name}.elab", EXAMPLES / f"{name}.stimulus.csv", duration)
       for name, duration in (("blink", "3s"), ("line_follower", "3s"), ("pneumatic_cylinder", "3600ms"),
                              ("pt100_sensor", "3500ms"))},
    "cd_to_dat": (EXAMPLES / "cd_to_dat.elab", None, "200ms"),
    # device ports with rates, float32 device data, tasks of several periods
    "multirate": (DATA / "multirate.elab", DATA / "multirate.stimulus.csv", "1500ms"),
    # a declared safe value: the led's initial value in the firmware and at the proxy's boot
    "safe_blink": (SAFE / "safe_blink.elab", EXAMPLES / "blink.stimulus.csv", "1500ms"),
}


# CSV for every example, VCD for the two with charts (the trace writer is the
# interpreter's, tested on every example in tests/interp).
RUNS = [(name, "csv") for name in CASES] + [("line_follower", "vcd"), ("pneumatic_cylinder", "vcd")]


@pytest.mark.parametrize("name,ext", RUNS)
def test_remote_trace_equals_native(name, ext, build_cache, tmp_path):
    model, stimulus, duration = CASES[name]
    native = tmp_path / f"native.{ext}"
    run_native(native_of(build_cache, model), native, duration, stimulus)

    devices = device_columns(stimulus, model, tmp_path / "devices.csv") if stimulus else None
    proxy = Proxy(proxy_of(build_cache, model), tmp_path / "link", "--fast",
                  *(["--stimulus", str(devices)] if devices else []))
    try:
        traced = tmp_path / f"remote.{ext}"
        args = ["--fast", "--duration", duration, "--trace", str(traced)]
        proc = remote(model, proxy.link, *args, *(["--stimulus", str(stimulus)] if stimulus else []))
        assert proc.returncode == 0, proc.stderr
        status, err = proxy.finish()  # STOP ends a host-board proxy
        assert status == 0, err
    finally:
        proxy.kill()
    expected = native.read_bytes()
    assert traced.read_bytes() == expected
    if ext == "csv" and stimulus is not None:
        assert expected.count(b"\n") > 20, "the stimulus should make the model move"


def test_a_tcp_link_gives_the_pty_links_trace(build_cache, tmp_path):
    """The host-board proxy on `--link tcp:PORT`, the host on
    `socket://127.0.0.1:PORT`: a real socket, the same lock-step trace as
    over a pty (and as the firmware)."""
    name = "pt100_sensor"
    model, stimulus, duration = CASES[name]
    devices = device_columns(stimulus, model, tmp_path / "devices.csv")
    traces = {}
    for tcp in (False, True):
        proxy = Proxy(proxy_of(build_cache, model), tmp_path / "link", "--fast", "--stimulus", str(devices), tcp=tcp)
        try:
            assert str(proxy.link).startswith("socket://127.0.0.1:") == tcp
            traces[tcp] = tmp_path / f"remote_{'tcp' if tcp else 'pty'}.csv"
            proc = remote(model, proxy.link, "--fast", "--duration", duration, "--trace", str(traces[tcp]),
                          "--stimulus", str(stimulus))
            assert proc.returncode == 0, proc.stderr
            status, err = proxy.finish()  # STOP ends it, over a socket too
            assert status == 0, err
        finally:
            proxy.kill()
    native = tmp_path / "native.csv"
    run_native(native_of(build_cache, model), native, duration, stimulus)
    assert traces[True].read_bytes() == traces[False].read_bytes() == native.read_bytes()


@pytest.mark.realtime
def test_real_time_paced_by_the_proxy(build_cache, tmp_path):
    """Without --fast the proxy's clock paces the run (the proxy does not
    wait for the host); the trace is the same."""
    import time

    name, duration = "pt100_sensor", "1s"
    model, stimulus = EXAMPLES / f"{name}.elab", EXAMPLES / f"{name}.stimulus.csv"
    native = tmp_path / "native.csv"
    run_native(native_of(build_cache, model), native, duration, stimulus)
    devices = device_columns(stimulus, model, tmp_path / "devices.csv")
    proxy = Proxy(proxy_of(build_cache, model), tmp_path / "link", "--stimulus", str(devices))
    try:
        traced = tmp_path / "remote.csv"
        started = time.monotonic()
        proc = remote(model, proxy.link, "--duration", duration, "--trace", str(traced), "--stimulus", str(stimulus))
        assert proc.returncode == 0, proc.stderr
        assert time.monotonic() - started >= 1.0  # real time: a second of it
        assert proxy.finish()[0] == 0
    finally:
        proxy.kill()
    assert traced.read_bytes() == native.read_bytes()


def test_a_run_that_the_link_cannot_carry_is_refused_with_its_numbers(tmp_path):
    proc = remote(EXAMPLES / "blink.elab", tmp_path / "nothing-there", "--baud", "115200")
    assert proc.returncode == 1
    assert ("the link cannot carry the device data in time: main at tick 0: 24 bytes per instant (UP 10, DOWN 14) "
            "take 2.083 ms at 115200 baud; the deadline is 1 ms") in proc.stderr
    assert not (tmp_path / "nothing-there").exists()
