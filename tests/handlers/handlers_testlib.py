"""Helpers of the device-handler tests: models with their own folders
(handler files beside them), builds through the command line, runs of the
host board, the AVR board's simulator and local execution."""

from __future__ import annotations

import os
import struct
import subprocess
import sys
from pathlib import Path

from firmware_builds import ROOT, Built, build, cli, run_program, write_model  # noqa: F401

run = run_program

LOGGER = ROOT / "examples" / "pt100_logger" / "pt100_logger.elab"
LOGGER_STIMULUS = LOGGER.with_name("pt100_logger.stimulus.csv")


def interpret(model: Path, *args, cache: Path, ok: bool = True) -> subprocess.CompletedProcess:
    """``easylab run MODEL ARGS`` with its own plug-in cache."""
    proc = subprocess.run([sys.executable, "-m", "easylab", "run", str(model), *map(str, args)], capture_output=True,
                          text=True, timeout=300, stdin=subprocess.DEVNULL, cwd=ROOT,
                          env={**os.environ, "EASYLAB_CACHE": str(cache)})
    if ok:
        assert proc.returncode == 0, proc.stderr
    return proc


def trace_rows(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    """A CSV trace's header and its rows by column."""
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    return header, [dict(zip(header, line.split(","))) for line in lines[1:]]


def eeprom_log(image: bytes, values: int, slot: int) -> list[tuple[int, list[int]]]:
    """The records of an I2cEepromLog memory (docs/stdlib.md): (sequence
    number, values) per written slot, in slot order."""
    records = []
    for at in range(0, len(image), slot):
        seq = struct.unpack_from("<H", image, at)[0]
        if seq == 0xFFFF:
            continue
        records.append((seq, list(struct.unpack_from(f"<{values}h", image, at + 2))))
    return records
