"""libFuzzer over the debug server's frame decoding and request dispatch,
under ASan and UBSan: at least 100,000 executions without a finding."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from debug_testlib import ROOT

FUZZ = ROOT / "fuzz"


def test_fuzz_frames_and_requests(tmp_path):
    if shutil.which("clang") is None:
        pytest.skip("clang is not installed")
    exe = tmp_path / "debug_fuzz"
    cmd = ["clang", "-g", "-O1", "-std=c99", "-Wall", "-Wextra", "-Werror",
           "-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all", "-DEL_DEBUG=1",
           "-DEL_DEBUG_BOARD_COMMANDS=1",  # local execution's model upload (boards/host/host_load.c) too
           f"-I{FUZZ / 'debug_include'}", f"-I{ROOT / 'runtime_c'}", str(FUZZ / "debug_fuzz.c"),
           str(FUZZ / "debug_fuzz_model.c"), *(str(ROOT / "runtime_c" / f) for f in
                                                ("el_debug.c", "el_debug_cobs.c", "el_crc16.c")),
           str(ROOT / "boards" / "host" / "host_load.c"), "-o", str(exe)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0 and "fuzzer" in proc.stderr and "cannot find" in proc.stderr:
        pytest.skip("clang's libFuzzer runtime is missing (Debian: libclang-rt-14-dev)")
    assert proc.returncode == 0, proc.stderr
    corpus = tmp_path / "corpus"
    shutil.copytree(FUZZ / "debug_corpus", corpus)  # the fuzzer adds to it: not in the tree
    run = subprocess.run([str(exe), str(corpus), "-runs=150000", "-max_total_time=120", "-rss_limit_mb=2048",
                          "-print_final_stats=1"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-4000:]
    done = [line for line in run.stderr.splitlines() if line.startswith("Done ")]
    assert done and int(done[0].split()[1]) >= 100_000, run.stderr[-2000:]
