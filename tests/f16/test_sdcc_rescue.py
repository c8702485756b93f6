"""sdcc 4.2 crashes on a narrowed bitwise cast (docs/boards.md, "When sdcc
crashes"): the real sdcc on the smallest such file, as written and as
generator/board/sdcc_rescue.py rewrites it."""

from __future__ import annotations

import subprocess

from easylab.board.sdcc_rescue import crashed, rescue_source

SOURCE = """\
#include <stdint.h>
uint8_t m;
uint8_t s;
float f;
void g(void) { m = (uint8_t)(((uint32_t)s * 3uL) | ((uint32_t)s << 8)); m = (uint8_t)(s + 1u); m = (uint8_t)f; }
"""
SDCC = ["sdcc", "-mmcs51", "--std-c89", "--model-large", "--stack-auto"]


def test_sdcc_crashes_on_the_file_as_written(tmp_path):
    src = tmp_path / "crash.c"
    src.write_text(SOURCE)
    proc = subprocess.run([*SDCC, "-c", "-o", str(tmp_path / "crash.rel"), str(src)], capture_output=True, text=True,
                          timeout=120)
    assert crashed(proc.returncode, proc.stdout + proc.stderr), (proc.returncode, proc.stderr)


def test_the_rewritten_file_compiles_and_only_bitwise_casts_change(tmp_path):
    src = tmp_path / "crash.c"
    src.write_text(SOURCE)
    pre = subprocess.run([*SDCC, "-E", str(src)], capture_output=True, text=True, timeout=120, check=True)
    text, changed = rescue_source(pre.stdout)
    assert changed == 1
    assert "(uint8_t) ((uint32_t) ((((uint32_t) s) * 3uL) | (((uint32_t) s) << 8)))" in text
    assert "(uint8_t) (s + 1u)" in text and "(uint8_t) f" in text
    safe = tmp_path / "safe.c"
    safe.write_text(text)
    proc = subprocess.run([*SDCC, "-c", "-o", str(tmp_path / "safe.rel"), str(safe)], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr


def test_an_error_in_the_c_is_not_a_crash():
    assert not crashed(1, "t.c:3: error 20: Undefined identifier 'x'")
    assert crashed(-11, "") and crashed(1, "Caught signal 11: SIGSEGV")
    assert crashed(1, "FATAL Compiler Internal Error in file 'SDCCopt.c' line number '834'")
