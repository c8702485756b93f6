"""Run a command in a private network namespace whose loopback carries
multicast: DDS discovery works there with no configuration, isolated from
every other DDS participant of the machine (the DDS tests and benchmark).

    python tools/netns.py COMMAND [ARG ...]

Needs unprivileged user namespaces (`unshare -rn`); no root.
"""

from __future__ import annotations

import shutil
import subprocess
import sys

# Inside the namespace only `lo` exists, down: bring it up with multicast.
_SETUP = 'ip link set lo up && ip link set lo multicast on && exec "$@"'


def namespace_command(command: list[str]) -> list[str]:
    """``command`` wrapped to run in a new user and network namespace."""
    return ["unshare", "-rn", "sh", "-c", _SETUP, "netns", *command]


def namespace_problem() -> str | None:
    """None when a private network namespace works here, else why not."""
    for tool in ("unshare", "ip"):
        if shutil.which(tool) is None:
            return f"'{tool}' is not installed (Debian packages util-linux and iproute2)"
    proc = subprocess.run(namespace_command(["true"]), capture_output=True, text=True, timeout=30)
    if proc.returncode != 0:
        return (f"`unshare -rn` (an unprivileged network namespace) is not permitted here: "
                f"{proc.stderr.strip() or 'exit status ' + str(proc.returncode)}; allow user namespaces "
                "(sysctl kernel.unprivileged_userns_clone=1, user.max_user_namespaces > 0)")
    return None


if __name__ == "__main__":
    problem = namespace_problem()
    if problem:
        sys.exit(f"netns: {problem}")
    sys.exit(subprocess.call(namespace_command(sys.argv[1:])))
