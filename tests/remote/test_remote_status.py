"""Overruns on the debug and service interfaces of `easylab remote`: with
latency injected on a real TCP link (a relay that holds the host's bytes
past the proxy's deadlines), the proxy counts overruns per task, the host
serves them as the status item `remote.acquire.overruns` (docs/ir.md,
"Status items") read by id over the debug protocol and as an input
register over Modbus TCP, and the trace records them as status events."""

from __future__ import annotations

import re

import signal
import subprocess
import sys
import time

from easylab.host_tools.debug_map import DebugMap
from easylab.host_tools.debug_protocol import DebugClient
from easylab.host_tools.service_map import load_map
from easylab.pipeline import lower_file
from easylab.remote.proxy import build_proxy
from remote_testlib import EASYLAB, EXAMPLES, LatencyRelay, Proxy, free_port

PT100 = EXAMPLES / "pt100_sensor.elab"


def until(condition, what: str, proc: subprocess.Popen, timeout: float = 120.0):
    """The first true value of ``condition()`` (which may fail while the
    host starts: its first run compiles the interfaces library), while
    ``proc`` runs."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            value = condition()
            if value:
                return value
        except Exception as err:  # not listening yet
            value = err
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, f"{what}: {value!r}"
        time.sleep(0.1)


def test_injected_latency_gives_overruns_on_the_debug_and_modbus_interfaces(tmp_path):
    """pt100_sensor (10 ms deadlines) with `remote overruns 255` and a 2 s
    watchdog, so that late values are held rather than ending the run; the
    relay holds the host's frames for 40 ms every 0.5 s."""
    from pymodbus.client import ModbusTcpClient

    model = tmp_path / "pt100_late.elab"
    model.write_text(PT100.read_text() + "modbus tcp port 1502\nremote watchdog 2 s overruns 255\n")
    program, result = lower_file(model)
    assert program is not None, result.report()
    proxy = Proxy(build_proxy(program, "host", tmp_path / "proxy").executable, tmp_path / "link", tcp=True)
    relay = LatencyRelay(str(proxy.link), stall_s=0.04, every_s=0.5)
    dbg, mb, maps, trace = free_port(), free_port(), tmp_path / "maps", tmp_path / "remote.csv"
    host = subprocess.Popen([*EASYLAB, "remote", str(model), "--target", relay.url, "--duration", "20s",
                             "--trace", str(trace), "--debug", f"tcp:{dbg}", "--modbus-tcp", str(mb),
                             "--maps", str(maps)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    try:
        client = until(lambda: DebugClient.open(f"socket://127.0.0.1:{dbg}", 2.0), "no debug interface", host)
        item = DebugMap.load(maps / "debug_map.json").item("remote.acquire.overruns")
        assert item.kind == "status" and not item.writable and item.type == "uint16"
        assert client.item_info(item.id)["kind"] == "status"
        # overruns counted by the proxy reach the host's debug interface while the run goes on
        debug_count = until(lambda: client.read([(item.id, item.type, 1)])[0], "no overrun over the debug link",
                            host, timeout=60)
        entry = next(e for e in load_map(maps / "service_map.json").items
                     if e.name == "remote.acquire.overruns")
        assert (entry.table, entry.access) == ("input", "ro")
        modbus = ModbusTcpClient("127.0.0.1", port=mb, timeout=2)
        assert modbus.connect()
        try:
            registers = modbus.read_input_registers(entry.address, count=1, device_id=1)
            assert not registers.isError(), registers
            assert registers.registers[0] >= debug_count > 0  # a counter only grows
            refused = modbus.write_register(entry.address, 0, device_id=1)  # input registers are read-only
            assert refused.isError()
        finally:
            modbus.close()
        # easylab-service reads it by name, as any item of the map
        tool = subprocess.run([sys.executable, "-m", "easylab.host_tools.service_cli", "--map",
                               str(maps / "service_map.json"), "--tcp", f"127.0.0.1:{mb}", "read",
                               "remote.acquire.overruns"], capture_output=True, text=True, timeout=60)
        assert tool.returncode == 0, tool.stderr
        name, value = tool.stdout.split(" = ")
        assert name == "remote.acquire.overruns" and int(value.split()[0]) >= debug_count
        client.close()
        host.send_signal(signal.SIGTERM)
        _, err = host.communicate(timeout=120)
        assert host.returncode == 0, err
        # the same word and numbers as the status item: per proxy task
        assert re.search(r"the proxy counted (\d+) overruns \(acquire \1\): the host's values came late", err), err
    finally:
        if host.poll() is None:
            host.kill()
            host.communicate()
        relay.close()
        proxy.kill()
    lines = trace.read_text().splitlines()
    events = [line.split(",") for line in lines if line.startswith("#status,")]
    assert events, "no overrun traced"
    counts = [int(e[3]) for e in events]
    assert all(e[2] == "remote.acquire.overruns" for e in events) and counts == sorted(counts) and counts[0] > 0
    assert [int(e[1]) for e in events] == sorted(int(e[1]) for e in events)
    rows = [line.split(",") for line in lines[1:] if not line.startswith("#")]
    assert all(len(r) == len(lines[0].split(",")) for r in rows)  # events are lines of their own, never columns


def test_status_events_are_lines_of_their_own_in_both_trace_formats(tmp_path):
    """A status event never adds a column: in CSV a `#status` line after the
    instant's row, in VCD a `$comment` under its time (one `#time` line
    per time, whether values changed then or not)."""
    from easylab.interp.trace import TraceWriter, columns_of

    program, _ = lower_file(EXAMPLES / "blink.elab")
    columns = columns_of(program)
    base = tuple(0 for _ in columns)
    changed = (1,) + base[1:]
    for name in ("t.csv", "t.vcd"):
        writer = TraceWriter(str(tmp_path / name), program, columns)
        writer.record(0, base)
        writer.event(0, "remote.blink.overruns", 1)
        writer.record(1000, changed)
        writer.record(2000, changed)
        writer.event(2000, "remote.blink.overruns", 2)
        writer.close(3000)
    csv_lines = (tmp_path / "t.csv").read_text().splitlines()
    assert [line for line in csv_lines if line.startswith("#")] == [
        "#status,0,remote.blink.overruns,1", "#status,2000,remote.blink.overruns,2"]
    assert csv_lines.index("#status,0,remote.blink.overruns,1") == 2  # after the header and instant 0's row
    assert all(len(line.split(",")) == len(columns) + 1 for line in csv_lines if not line.startswith("#"))
    vcd = (tmp_path / "t.vcd").read_text().split("$enddefinitions $end\n")[1].splitlines()
    times = [line for line in vcd if line.startswith("#")]
    assert times == ["#0", "#1000", "#2000", "#3000"]
    assert vcd[vcd.index("#2000") + 1] == "$comment status remote.blink.overruns 2 $end"
    assert "$comment status remote.blink.overruns 1 $end" in vcd[:vcd.index("#1000")]
