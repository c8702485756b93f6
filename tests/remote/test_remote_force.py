"""Forcing and conditional breakpoints in remote execution (`easylab
remote --debug`, docs/protocol.md "Forcing and conditional breakpoints"):
the sensor the proxy reads is forced on the host side at every instant
(the trace shows it while the proxy's stimulus says otherwise), a
conditional breakpoint halts at the instant it turns true, and after the
release the proxy's reads come through again."""

from __future__ import annotations

import csv
import subprocess
import time

from easylab.host_tools.debug_map import DebugMap
from easylab.host_tools.debug_protocol import K
from remote_testlib import EASYLAB, EXAMPLES, Proxy, device_columns, proxy_of
from test_remote_debug import connect, free_port

MODEL = EXAMPLES / "pneumatic_cylinder.elab"
STIMULUS = EXAMPLES / "pneumatic_cylinder.stimulus.csv"


def _wait_halted(client, timeout: float = 30.0):
    deadline = time.monotonic() + timeout
    while True:
        f = client.flags()
        if f.halted:
            return f
        assert time.monotonic() < deadline, f"not halted: {f}"
        time.sleep(0.01)


def _value_at(rows: list[dict], column: str, time_us: int) -> str | None:
    value = None
    for r in rows:
        if int(r["time_us"]) > time_us:
            break
        value = r[column]
    return value


def test_force_and_a_conditional_breakpoint_over_the_proxy(build_cache, tmp_path):
    devices = device_columns(STIMULUS, MODEL, tmp_path / "devices.csv")
    proxy = Proxy(proxy_of(build_cache, MODEL), tmp_path / "link", "--fast", "--stimulus", str(devices))
    port, maps, trace = free_port(), tmp_path / "maps", tmp_path / "remote.csv"
    host = subprocess.Popen([*EASYLAB, "remote", str(MODEL), "--target", str(proxy.link), "--fast",
                             "--duration", "600ms", "--trace", str(trace), "--stimulus", str(STIMULUS),
                             "--debug", f"tcp:{port},halt", "--maps", str(maps)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    client = None
    try:
        client = connect(port, host)
        client.hello()
        _wait_halted(client)
        m = DebugMap.load(maps / "debug_map.json")
        end_out, cycles = m.item("end_out.level"), m.item("cycles")
        assert client.hello_info.force_slots == K.FORCE_MAX
        client.force(end_out.id, "bool", 1)
        slot = client.bp_when(cycles.id, cycles.type, ">=", 1)
        client.run()
        f = _wait_halted(client)
        # the sensor forced from the start: Extended at 25 ms, `cycles` seen at the next instant
        assert (f.why, f.location.kind, f.breakpoint, f.tick) == ("breakpoint", K.P_CONDITION, slot, 6)
        assert [x.item for x in client.forced()] == [end_out.id]
        client.release()
        client.bp_clear()
        client.run()
        _, err = host.communicate(timeout=120)
        assert host.returncode == 0, err
        status, proxy_err = proxy.finish()
        assert status == 0, proxy_err
    finally:
        if client:
            client.close()
        if host.poll() is None:
            host.kill()
            host.communicate()
        proxy.kill()
    with open(trace, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert all(_value_at(rows, "end_out.level", t) == "1" for t in range(0, 30001, 5000))
    assert _value_at(rows, "end_out.level", 35000) == "0"  # released: the proxy's reading again
    assert _value_at(rows, "end_out.level", 200000) == "1"  # and its stimulus's change at 160 ms
