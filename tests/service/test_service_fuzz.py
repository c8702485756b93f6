"""libFuzzer over the Modbus slave's RTU and TCP request parsers and the
persistence records (fuzz/modbus_fuzz.c), under ASan and UBSan, for at
least 100,000 executions from the corpus in fuzz/modbus_corpus/ (copied:
the run adds nothing to the tree)."""

from __future__ import annotations

import re
import shutil
import subprocess

import pytest

from svc_testlib import ROOT

RUNTIME = ROOT / "runtime_c"
SOURCES = [ROOT / "fuzz" / "modbus_fuzz.c"] + [RUNTIME / f for f in ("el_modbus.c", "el_service.c", "el_persist.c",
                                                                       "el_crc16.c")]


@pytest.mark.skipif(shutil.which("clang") is None, reason="clang is not installed")
def test_fuzz_modbus_parsers(tmp_path):
    exe = tmp_path / "modbus_fuzz"
    cmd = ["clang", "-g", "-O1", "-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all",
           "-Wall", "-Wextra", "-Werror", f"-I{RUNTIME}", *map(str, SOURCES), "-o", str(exe)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if proc.returncode != 0 and "libclang_rt.fuzzer" in proc.stderr:
        pytest.skip("clang's libFuzzer runtime is missing (Debian: libclang-rt-14-dev)")
    assert proc.returncode == 0, proc.stderr
    corpus = tmp_path / "corpus"
    shutil.copytree(ROOT / "fuzz" / "modbus_corpus", corpus)
    work = tmp_path / "work"
    work.mkdir()
    proc = subprocess.run([str(exe), "-runs=150000", "-seed=1", "-max_len=700", "-max_total_time=120",
                           str(work), str(corpus)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-4000:]
    done = re.search(r"Done (\d+) runs", proc.stderr)
    assert done and int(done.group(1)) >= 100000, proc.stderr[-2000:]
