"""Helpers of the AVR board's tests: the CLI, cross builds, the simavr
harness, host builds to compare with.

Everything goes through the ``easylab`` command line as a user would run
it (``python -m easylab`` with this interpreter and the inherited
environment), then through the built programs. CI has avr-gcc, avr-libc,
simavr and libsimavr: nothing here is skipped.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
DATA = HERE / "data"
EXAMPLES = sorted((ROOT / "examples").glob("*.elab"))
EXAMPLE_NAMES = [p.stem for p in EXAMPLES]


def debug_client_class():
    """easylab.host_tools' DebugClient (installed, or from this source tree
    where `easylab` is generator/ alone)."""
    import easylab

    try:
        import easylab.host_tools  # noqa: F401
    except ImportError:
        easylab.__path__.append(str(ROOT))
    from easylab.host_tools.debug_protocol import DebugClient

    return DebugClient


def cli(*args, timeout: float = 300, cwd: Path | None = None) -> subprocess.CompletedProcess:
    """``python -m easylab ARGS`` (text)."""
    return subprocess.run([sys.executable, "-m", "easylab", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd or ROOT, env=dict(os.environ), timeout=timeout, stdin=subprocess.DEVNULL)


@dataclass
class Built:
    proc: subprocess.CompletedProcess
    elf: Path | None
    simulator: Path | None

    @property
    def lines(self) -> list[str]:
        return self.proc.stdout.strip().splitlines()

    @property
    def size_line(self) -> str:
        return next(line for line in self.lines if "flash" in line and "RAM" in line)


def avr_build(model: Path | str, out: Path, *args: str, ok: bool = True) -> Built:
    """``easylab build MODEL --board avr ARGS -o OUT``."""
    proc = cli("build", model, "--board", "avr", *args, "-o", out)
    if ok:
        assert proc.returncode == 0, f"build of {model} {' '.join(args)} failed:\n{proc.stdout}{proc.stderr}"
        elf = Path(proc.stdout.strip().splitlines()[-1])
        assert elf.suffix == ".elf" and elf.is_file(), proc.stdout
        sim = next((Path(line.split(": ", 1)[1]) for line in proc.stdout.splitlines()
                    if line.startswith("simulator: ")), None)
        return Built(proc, elf, sim)
    assert proc.returncode != 0, f"build of {model} {' '.join(args)} should fail:\n{proc.stdout}"
    return Built(proc, None, None)


def host_build(model: Path | str, out: Path) -> Path:
    proc = cli("build", model, "--board", "host", "-o", out)
    assert proc.returncode == 0, f"host build of {model} failed:\n{proc.stdout}{proc.stderr}"
    return Path(proc.stdout.strip().splitlines()[-1])


def run(exe: Path, *args, timeout: float = 120, ok: bool = True) -> subprocess.CompletedProcess:
    proc = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)
    if ok:
        assert proc.returncode == 0, f"{exe.name} {' '.join(map(str, args))}: status {proc.returncode}\n{proc.stderr}"
    return proc


def stimulus_of(name: str) -> Path | None:
    """The stimulus the equivalence tests use for an example: this folder's
    data/, else the example's own, else none."""
    for p in (DATA / f"{name}.stimulus.csv", ROOT / "examples" / f"{name}.stimulus.csv"):
        if p.is_file():
            return p
    return None
