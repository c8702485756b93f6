"""`easylab remote --debug` and `--modbus-rtu`: the host side serves the model's debug
interface as `easylab run` does (the firmware's own server in the
interfaces library), while the proxy drives the devices: a debugger halts
the run at its start, reads and writes params, and the proxy-driven trace
follows the written value; a model sent over the debug link that changes
the device model is refused."""

from __future__ import annotations

import signal
import subprocess
import time

from easylab.host_tools.debug_map import DebugMap
from easylab.pipeline import lower_file
from remote_testlib import EASYLAB, EXAMPLES, Proxy, debugged_remote_run, proxy_of

BLINK = EXAMPLES / "blink.elab"


def test_the_host_side_serves_the_debug_interface(build_cache, tmp_path):
    program, _ = lower_file(BLINK)
    proxy = Proxy(proxy_of(build_cache, BLINK), tmp_path / "link", "--fast")
    with debugged_remote_run(proxy, BLINK, tmp_path) as run:
        client, host, maps, trace = run.client, run.host, run.maps, run.trace
        assert client.hello().program_id == program.program_id
        deadline = time.monotonic() + 10
        while not client.flags().halted:  # halted before the first instant
            assert time.monotonic() < deadline, "not halted"
            time.sleep(0.01)
        half = DebugMap.load(maps / "debug_map.json").item("half_period")
        assert client.read([(half.id, half.type, half.count)]) == [500]
        client.write(half.id, half.type, 100)
        client.run()
        # `load` over the debug link (checked while running): a model whose
        # device model differs is refused, the run goes on.
        moved = client.replace_model(BLINK.read_bytes().replace(b'"PB5"', b'"PB4"'))
        assert moved.state == "refused" and "the edit changes the device model (devices led)" in moved.message
        assert host.poll() is None and not client.flags().halted
        deadline = time.monotonic() + 60
        while client.flags().tick < 400:  # logical time past 0.4 s (1 ms ticks)
            assert time.monotonic() < deadline, "the run does not go on"
            time.sleep(0.05)
        host.send_signal(signal.SIGTERM)  # the run ends at the next instant; STOP ends the proxy
    rows = [line.split(",") for line in trace.read_text().splitlines()]
    column = rows[0].index("led.level")
    changes = [int(r[0]) for r, before in zip(rows[2:], rows[1:]) if r[column] != before[column]]
    # The written half period from the first instant on: the led goes on at
    # the first deadline (1 ms), then toggles every 100 ms, not 500.
    assert changes[:4] == [1000, 101000, 201000, 301000], changes[:5]


def test_the_host_side_serves_the_modbus_interface(build_cache, tmp_path):
    """`easylab remote --modbus-rtu`: pt100_sensor's service interface on a
    pty while a proxy drives its devices; a param written over Modbus is in
    the registers and in the trace; `--nvram` keeps it."""
    from sim_modbus import read_holding

    from pymodbus.client import ModbusSerialClient

    model = EXAMPLES / "pt100_sensor.elab"
    proxy = Proxy(proxy_of(build_cache, model), tmp_path / "link", "--fast")
    mb, trace, nvram = tmp_path / "mb", tmp_path / "remote.csv", tmp_path / "nv.bin"
    host = subprocess.Popen([*EASYLAB, "remote", str(model), "--target", str(proxy.link), "--fast",
                             "--trace", str(trace), "--modbus-rtu", f"pty:{mb}", "--nvram", str(nvram)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120  # the first run compiles the interfaces library
        while not mb.exists():
            assert host.poll() is None, host.communicate()
            assert time.monotonic() < deadline, "the Modbus interface did not open"
            time.sleep(0.1)
        client = ModbusSerialClient(port=str(mb), baudrate=115200, parity="N", timeout=2)  # a pty: no line settings
        assert client.connect()
        try:
            assert read_holding(client, 3) == [1000, 0, 800]  # cal_gain, cal_offset, alarm_high
            assert not client.write_register(1, 25, device_id=17).isError()
            assert read_holding(client, 3) == [1000, 25, 800]
        finally:
            client.close()
        host.send_signal(signal.SIGTERM)
        _, err = host.communicate(timeout=120)
        assert host.returncode == 0, err
        status, proxy_err = proxy.finish()
        assert status == 0, proxy_err
    finally:
        if host.poll() is None:
            host.kill()
            host.communicate()
        proxy.kill()
    rows = [line.split(",") for line in trace.read_text().splitlines()]
    column = rows[0].index("cal_offset")
    assert rows[1][column] == "0" and rows[-1][column] == "25"
    assert nvram.stat().st_size > 0
