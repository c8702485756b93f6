"""Helpers of the PIC18 board's tests: builds through the ``easylab``
command line as a user runs it, the gpsim harness, host builds to compare
with. CI has the board's toolchain (`make setup` builds sdcc's pic16 port
into the cache) and Debian's gpsim: nothing here is skipped."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

from firmware_builds import EXAMPLE_NAMES, EXAMPLES, ROOT, Built, build, cli, stimulus_of  # noqa: F401

HERE = Path(__file__).resolve().parent
MODELS = HERE / "models"
DATA = HERE / "data"

SIZE_LINE = re.compile(r"^(pic18f\d+): program memory (\d+) of (\d+) bytes .*RAM (\d+) of (\d+) bytes")


def pic18_build(model: Path | str, out: Path, *args: str, ok: bool = True) -> Built:
    """``easylab build MODEL --board pic18 ARGS -o OUT``."""
    built = build(model, "pic18", out, *args, ok=ok)
    if ok:
        assert built.elf.suffix == ".hex" and built.elf.is_file(), built.proc.stdout
    return built


def sizes(built: Built) -> dict:
    """The size line of a build: mcu, flash, flash_max, ram, ram_max."""
    line = next((ln for ln in built.lines if SIZE_LINE.match(ln)), None)
    assert line, built.proc.stdout
    m = SIZE_LINE.match(line)
    return {"mcu": m.group(1), "flash": int(m.group(2)), "flash_max": int(m.group(3)), "ram": int(m.group(4)),
            "ram_max": int(m.group(5))}


def write_model(tmp_path: Path, name: str, body: str) -> Path:
    path = tmp_path / f"{name}.elab"
    path.write_text(f"model {name}\nimport std\n\n{body}", encoding="utf-8")
    return path


def run(exe: Path, *args, timeout: float = 300, ok: bool = True) -> subprocess.CompletedProcess:
    """A program (a harness, a host build) to its end; ``ok``: status 0."""
    proc = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)
    if ok:
        assert proc.returncode == 0, f"{exe.name} {' '.join(map(str, args))}: status {proc.returncode}\n{proc.stderr}"
    return proc


def pins_rows(path: Path) -> list[tuple[int, int, str, int]]:
    """A --pins CSV: (cycle, time_us, pin, value) rows."""
    lines = path.read_text().splitlines()
    assert lines[0] == "cycle,time_us,pin,value", lines[:1]
    return [(int(c), int(t), p, int(v)) for c, t, p, v in (line.split(",") for line in lines[1:])]


def changes(values) -> list:
    """A sequence without its repeats: the values as they change."""
    out: list = []
    for v in values:
        if not out or out[-1] != v:
            out.append(v)
    return out
