"""Forcing and conditional breakpoints in remote execution (`easylab
remote --debug`, docs/protocol.md "Forcing and conditional breakpoints"):
the sensor the proxy reads is forced on the host side at every instant
(the trace shows it while the proxy's stimulus says otherwise), a
conditional breakpoint halts at the instant it turns true, and after the
release the proxy's reads come through again."""

from __future__ import annotations

import csv
import sys
from pathlib import Path

from easylab.host_tools.debug_map import DebugMap
from easylab.host_tools.debug_protocol import K
from remote_testlib import EXAMPLES, Proxy, debugged_remote_run, device_columns, proxy_of

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "debug"))
from debug_testlib import wait_halted  # noqa: E402

MODEL = EXAMPLES / "pneumatic_cylinder.elab"
STIMULUS = EXAMPLES / "pneumatic_cylinder.stimulus.csv"


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
    with debugged_remote_run(proxy, MODEL, tmp_path, "--duration", "600ms", "--stimulus", str(STIMULUS)) as run:
        client, maps, trace = run.client, run.maps, run.trace
        client.hello()
        wait_halted(client, 30.0)
        m = DebugMap.load(maps / "debug_map.json")
        end_out, cycles = m.item("end_out.level"), m.item("cycles")
        assert client.hello_info.force_slots == K.FORCE_MAX
        client.force(end_out.id, "bool", 1)
        slot = client.bp_when(cycles.id, cycles.type, ">=", 1)
        client.run()
        f = wait_halted(client, 30.0)
        # the sensor forced from the start: Extended at 25 ms, `cycles` seen at the next instant
        assert (f.why, f.location.kind, f.breakpoint, f.tick) == ("breakpoint", K.P_CONDITION, slot, 6)
        assert [x.item for x in client.forced()] == [end_out.id]
        client.release()
        client.bp_clear()
        client.run()
    with open(trace, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert all(_value_at(rows, "end_out.level", t) == "1" for t in range(0, 30001, 5000))
    assert _value_at(rows, "end_out.level", 35000) == "0"  # released: the proxy's reading again
    assert _value_at(rows, "end_out.level", 200000) == "1"  # and its stimulus's change at 160 ms
