"""Helpers of the multi-core tests: the generators of the random SDF tests
and of the back-to-back campaign, reused, and builds with ``--cores``."""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
TESTS = HERE.parent
for folder in ("native", "crosscheck"):
    if str(TESTS / folder) not in sys.path:
        sys.path.insert(0, str(TESTS / folder))

from native_testlib import DATA, EXAMPLES, cli, run  # noqa: E402

__all__ = ["DATA", "EXAMPLES", "build_cores", "cli", "run"]


def build_cores(model: Path, out: Path, cores: int, *, cflags: str = "-O1", always: bool = True) -> tuple[Path, str]:
    """Build ``model`` for the host board on ``cores`` cores (``always``:
    parallel whatever the prediction); (the executable, what the build printed)."""
    args = ["build", model, "--board", "host", "-o", out, f"--cflags={cflags}"]
    if cores > 1:
        args += ["--cores", str(cores)] + (["--parallel", "always"] if always else [])
    proc = cli(*args)
    assert proc.returncode == 0, f"easylab {' '.join(map(str, args))} failed:\n{proc.stdout}{proc.stderr}"
    return Path(proc.stdout.strip().splitlines()[-1]), proc.stdout
