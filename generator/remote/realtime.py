"""How `easylab remote` keeps real time (docs/remote.md, "Real time at 1
kHz"): waiting for the proxy's frames by polling the link at short
deadlines, and with `--realtime` SCHED_FIFO and locked memory where the
system allows them, and a clear word where it does not."""

from __future__ import annotations

import os

# Above every ordinary process, below the kernel's own real-time threads.
PRIORITY = 10
_MCL_CURRENT, _MCL_FUTURE = 1, 2


# Deadlines up to this long are waited for by polling the link (`--wait
# auto`): a process asleep in the kernel on an idle machine was woken up to
# several milliseconds after its frame came (a virtual machine's CPU halts
# when idle), three late values in a row at 1 kHz. Longer deadlines leave
# room for such a wake-up, and polling would keep a CPU busy for nothing.
POLL_DEADLINES_UP_TO_US = 5000
WAITS = ("auto", "poll", "sleep")


def polls_its_link(wait: str, realtime: bool, deadline_us: int | None) -> bool:
    """Whether a real-time run waits for its frames by polling the link:
    `--wait poll`, or `auto` at a deadline of at most POLL_DEADLINES_UP_TO_US
    without `--realtime` (under SCHED_FIFO a polling process would keep
    every ordinary process off its CPU, the kernel's workers that deliver a
    pty's bytes included; its wake-up preempts whatever runs)."""
    if wait != "auto":
        return wait == "poll"
    return not realtime and deadline_us is not None and deadline_us <= POLL_DEADLINES_UP_TO_US


def go_real_time(target: str) -> list[str]:
    """Make this process SCHED_FIFO at PRIORITY with its memory locked, as
    far as allowed; the warnings to print (none when all went well)."""
    said = []
    if not target.startswith("socket://"):
        said.append(f"warning: --realtime with {target}: the kernel hands a pty's or a serial port's bytes to this "
                    "process in a worker thread of ordinary priority, which a real-time process and its peer can "
                    "starve; a TCP link (socket://HOST:PORT) does not have that step")
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(PRIORITY))
    except (AttributeError, OSError) as err:
        reason = getattr(err, "strerror", None) or str(err)
        said.append(f"warning: real-time scheduling is not allowed here ({reason}): the run goes on with ordinary "
                    "scheduling, and a busy machine may make it miss 1 ms deadlines (root, CAP_SYS_NICE or an "
                    "rtprio limit in /etc/security/limits.conf allow it)")
    import ctypes  # here: `easylab`'s other commands need not load it
    import ctypes.util

    libc = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
    if libc.mlockall(_MCL_CURRENT | _MCL_FUTURE) != 0:
        said.append(f"warning: this process's memory cannot be locked ({os.strerror(ctypes.get_errno())}): a page "
                    "fault may delay an answer (CAP_IPC_LOCK or a memlock limit allow it)")
    return said
