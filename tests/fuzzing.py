"""libFuzzer targets of fuzz/ for every suite: built with clang under ASan
and UBSan (-Wall -Wextra -Werror), then run from a copy of their seed
corpus (the run adds inputs to it, never to the tree) for a fixed number of
executions, which must all pass."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FUZZ = ROOT / "fuzz"
RUNTIME = ROOT / "runtime_c"
RUNS = 150_000
MIN_RUNS = 100_000


def run_fuzzer(tmp_path: Path, name: str, sources: list[Path], corpus: str, cflags: tuple[str, ...] = (),
               includes: tuple[Path, ...] = (), args: tuple[str, ...] = ()) -> str:
    """Build fuzz target ``name`` from ``sources`` (with runtime_c/ and
    ``includes`` on the include path) and run it on a copy of
    fuzz/``corpus``: at least MIN_RUNS executions without a finding.
    Returns libFuzzer's report (stderr)."""
    if shutil.which("clang") is None:
        pytest.skip("clang is not installed")
    exe = tmp_path / name
    cmd = ["clang", "-g", "-O1", "-std=c99", "-Wall", "-Wextra", "-Werror", "-fsanitize=fuzzer,address,undefined",
           "-fno-sanitize-recover=all", *cflags, *(f"-I{d}" for d in (*includes, RUNTIME)), *map(str, sources),
           "-o", str(exe)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if proc.returncode != 0 and "libclang_rt.fuzzer" in proc.stderr:
        pytest.skip("clang's libFuzzer runtime is missing (Debian: libclang-rt-14-dev)")
    assert proc.returncode == 0, proc.stderr
    seeds = tmp_path / "corpus"
    shutil.copytree(FUZZ / corpus, seeds)
    run = subprocess.run([str(exe), str(seeds), f"-runs={RUNS}", "-seed=1", "-max_total_time=120",
                          "-rss_limit_mb=2048", "-print_final_stats=1", *args],
                         capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-4000:]
    done = re.search(r"^Done (\d+) runs", run.stderr, re.MULTILINE)
    assert done and int(done.group(1)) >= MIN_RUNS, run.stderr[-2000:]
    return run.stderr
