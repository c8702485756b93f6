"""Helpers of the tests of peers that must not stall a host program's loop
(tests/service/test_service_peers.py, tests/debug/test_debug_peers.py,
tests/remote/test_remote_peers.py): a fast periodic task, real-time
scheduling where the system allows it, the program's own overrun report."""

from __future__ import annotations

import re
import shutil
import socket
import subprocess
import time

import pytest


# How a host program reports its dispatcher's late activations at its end:
# a firmware as overruns, a proxy as its own lateness (its overruns are the
# host's late values, docs/remote.md).
LATENESS_LABELS = ("overruns:", "behind its clock (instants processed after their deadlines):")


def overruns(stderr: str) -> int:
    """The late activations the host program reports at its end ("PROG:
    overruns: TASK N ...", a proxy's "PROG: behind its clock (...): TASK N
    ...")."""
    return sum(int(n) for line in stderr.splitlines() for label in LATENESS_LABELS if label in line
               for n in re.findall(r" (\d+)\b", line.split(label, 1)[1]))


def real_time_prefix() -> list[str]:
    """`chrt -f 10` where the system allows real-time scheduling, else
    nothing: under SCHED_FIFO the firmware's 5 ms deadlines measure its own
    loop, not the other jobs of a loaded machine."""
    chrt = shutil.which("chrt")
    if chrt and subprocess.run([chrt, "-f", "10", "true"], capture_output=True).returncode == 0:
        return [chrt, "-f", "10"]
    return []


def skip_unless_deadlines_hold(prefix: list[str], baseline_stderr) -> None:
    """Without real-time scheduling, a loaded machine alone may cost 5 ms
    deadlines: skip when a run with no peer at all (``baseline_stderr()``,
    the stderr of such a run) misses one."""
    if prefix:
        return
    if overruns(baseline_stderr()):
        pytest.skip("this machine misses 5 ms deadlines with no peer at all, and real-time "
                    "scheduling (chrt -f) is not allowed here")


def non_reading_client(port: int) -> socket.socket:
    """A client with the smallest receive buffer, which never reads."""
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.connect(("127.0.0.1", port))
    s.setblocking(False)
    return s


def flood_without_reading(proc: subprocess.Popen, port: int, seconds: float, next_burst, served_by_reader
                          ) -> tuple[int, bool]:
    """Send ``next_burst()`` to the program's TCP port for ``seconds`` (or
    until it exits) from a client that never reads, reconnecting whenever
    the program drops it; after the first drop, ask ``served_by_reader()``
    (a client that reads) whether the program still serves others. Returns
    (drops, served)."""
    drops = 0
    served = False
    client = non_reading_client(port)
    try:
        end = time.monotonic() + seconds
        while time.monotonic() < end and proc.poll() is None:
            try:
                client.send(next_burst())
            except BlockingIOError:
                time.sleep(0.001)  # both socket buffers full: the program has stopped taking requests
            except (ConnectionResetError, BrokenPipeError):
                drops += 1
                client.close()
                if not served:  # a client that reads is served meanwhile
                    served = served_by_reader()
                client = non_reading_client(port)
    finally:
        client.close()
    return drops, served
