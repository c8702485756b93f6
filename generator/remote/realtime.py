"""Real-time scheduling for `easylab remote --realtime` (docs/remote.md,
"Real time at 1 kHz"): SCHED_FIFO and locked memory where the system allows
them, and a clear word where it does not."""

from __future__ import annotations

import ctypes
import ctypes.util
import os

# Above every ordinary process, below the kernel's own real-time threads.
PRIORITY = 10
_MCL_CURRENT, _MCL_FUTURE = 1, 2


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
    libc = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
    if libc.mlockall(_MCL_CURRENT | _MCL_FUTURE) != 0:
        said.append(f"warning: this process's memory cannot be locked ({os.strerror(ctypes.get_errno())}): a page "
                    "fault may delay an answer (CAP_IPC_LOCK or a memlock limit allow it)")
    return said
