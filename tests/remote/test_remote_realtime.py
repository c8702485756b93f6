"""`easylab remote --realtime` (generator/remote/realtime.py): SCHED_FIFO
and locked memory where the system allows them, a clear word where it does
not, and a warning for links whose bytes pass a kernel worker thread."""

from __future__ import annotations

import os
import subprocess
import sys

import realtime_peers

PROBE = ("import os, json; from easylab.remote.realtime import go_real_time; "
         "said = go_real_time({target!r}); print(json.dumps([said, os.sched_getscheduler(0)]))")


def probe(target: str) -> tuple[list[str], int]:
    import json

    proc = subprocess.run([sys.executable, "-c", PROBE.format(target=target)], capture_output=True, text=True,
                          timeout=60, check=True)
    said, policy = json.loads(proc.stdout)
    return said, policy


def test_a_tcp_link_goes_real_time_where_allowed_or_says_why_not():
    said, policy = probe("socket://127.0.0.1:5000")
    if realtime_peers.real_time_prefix():  # this system allows SCHED_FIFO
        assert policy == os.SCHED_FIFO
        assert not [s for s in said if "scheduling" in s], said
    else:
        assert policy == os.SCHED_OTHER
        assert any("real-time scheduling is not allowed here" in s for s in said), said


def test_a_pty_or_serial_link_is_warned_about():
    said, _ = probe("/dev/ttyUSB0")
    assert any("a TCP link (socket://HOST:PORT) does not have that step" in s for s in said), said
