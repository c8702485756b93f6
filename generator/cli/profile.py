"""Measured costs of actor firings: a profiling run of the host build
(``easylab analyze --cores N --profile``, docs/multicore.md).

The host program is built with every actor firing timed (a release build:
no debug interface), run in virtual time (``--fast``) for ``duration``
with the model's stimulus if one is given, and its profile read back: the
mean nanoseconds of one firing of each actor instance, by
``"dataflow.instance"``, the keys ir/multicore.py takes.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

from ..ir.program import Program


class ProfileError(Exception):
    """The profiling build or run failed; the message says which and why."""


def profile_program(program: Program, work_dir: Path, stimulus: Path | None = None,
                    duration: str = "2s") -> dict[str, int]:
    """ns per firing by ``"dataflow.instance"`` (instances never fired are left out)."""
    from ..build import BuildError, build

    try:
        built = build(program, "host", work_dir / "build", release=True, profile=True)
    except BuildError as err:
        raise ProfileError(f"the profiling build failed: {err}") from None
    out = work_dir / "profile.txt"
    cmd = [str(built.executable), "--fast", "--duration", duration]
    if stimulus is not None:
        cmd += ["--stimulus", str(stimulus)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL,
                          env={**os.environ, "EASYLAB_PROFILE": str(out)})
    if proc.returncode != 0 or not out.exists():
        raise ProfileError(f"the profiling run failed (exit status {proc.returncode}): {proc.stderr.strip()}")
    return read_profile(out.read_text(encoding="utf-8"))


def read_profile(text: str) -> dict[str, int]:
    """Parse the lines ``name firings ns`` of a profile."""
    costs = {}
    for line in text.splitlines():
        name, firings, ns = line.split()
        if int(firings) > 0:
            costs[name] = max(int(ns) // int(firings), 1)
    return costs
