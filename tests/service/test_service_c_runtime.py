"""The service interface's C: warning-free with gcc and clang (-Wall -Wextra
-Werror -pedantic, C99), avr-gcc for the ATmega328P, a 16-bit int (clang
for the MSP430, sdcc for the STM8) and C89 with -pedantic-errors for the
F16 port; the generated service_tables.c too."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from svc_testlib import ROOT

RUNTIME = ROOT / "runtime_c"
FILES = ["el_modbus.c", "el_service.c", "el_persist.c", "el_crc16.c"]
STRICT = ["-Wall", "-Wextra", "-Werror", "-pedantic"]


def compile_c(cc: str, flags: list[str], sources, tmp_path) -> None:
    for src in sources:
        cmd = [cc, *flags, f"-I{RUNTIME}", str(src)]
        if cc == "sdcc":
            cmd = ["timeout", "120", *cmd, "-o", f"{tmp_path}/"]
        elif "-fsyntax-only" not in flags:
            cmd += ["-o", str(tmp_path / "x.o")]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=180, cwd=tmp_path)
        text = proc.stdout + proc.stderr
        assert proc.returncode == 0 and "warning" not in text.lower() and (cc == "sdcc" or not proc.stderr), \
            f"{' '.join(cmd)}\n{text}"


@pytest.mark.parametrize("cc, flags", [
    ("gcc", ["-c", "-std=c99", "-O2", *STRICT, "-Wconversion", "-Wshadow"]),
    ("clang", ["-c", "-std=c99", "-O2", *STRICT, "-Wshadow"]),
    ("avr-gcc", ["-c", "-mmcu=atmega328p", "-Os", "-std=c99", *STRICT]),
    # 16-bit int (the F16 port's proxies): clang for the MSP430, sdcc for the STM8 (no unions by value).
    ("clang", ["--target=msp430-none-elf", "-std=c99", *STRICT, "-fsyntax-only"]),
    ("sdcc", ["-mstm8", "--std-c99", "-c"]),
    # el_types.h's static helpers are unused here, and C89 has no inline: -Wno-unused-function.
    ("gcc", ["-c", "-std=c89", "-pedantic-errors", "-Wall", "-Wextra", "-Werror", "-Wno-unused-function"]),
])
def test_runtime_files_compile_without_warnings(cc, flags, tmp_path):
    if shutil.which(cc) is None:
        pytest.skip(f"{cc} is not installed")
    compile_c(cc, flags, [RUNTIME / f for f in FILES], tmp_path)


@pytest.mark.parametrize("cc, flags", [
    ("avr-gcc", ["-c", "-mmcu=atmega2560", "-Os", "-std=c99", *STRICT]),
    ("clang", ["-c", "-std=c99", *STRICT]),
    ("sdcc", ["-mstm8", "--std-c99", "-c"]),
])
def test_generated_tables_compile_for_other_targets(cc, flags, builds, tmp_path):
    if shutil.which(cc) is None:
        pytest.skip(f"{cc} is not installed")
    for model in ("pt100_sensor", "service_all"):
        compile_c(cc, flags, [builds(model).out / "service_tables.c"], tmp_path)
