"""libFuzzer targets of fuzz/ for every suite: built with clang under ASan
and UBSan (-Wall -Wextra -Werror), then run from a copy of their seed
corpus (the run adds inputs to it, never to the tree) for a fixed number of
executions, which must all pass.

The CRC (runtime_c/el_crc16.c) is built without the fuzzer's coverage
instrumentation, still under ASan and UBSan: its branches follow the data's
bits, not the code's paths, and tracing them cost the remote target half
its time while adding features that guide nothing.

`make fuzz` runs every target to EASYLAB_FUZZ_RUNS executions (10^7) and
writes each one's figures to build/fuzz/figures.md (docs/testing.md)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FUZZ = ROOT / "fuzz"
RUNTIME = ROOT / "runtime_c"
RUNS = int(os.environ.get("EASYLAB_FUZZ_RUNS", "150000"))
MIN_RUNS = min(RUNS, 100_000)
# Wall-clock bounds: the suite's runs take seconds; `make fuzz` runs up to
# about 10,000 executions a second on a slow target.
MAX_SECONDS = max(120, RUNS // 2_000)
UNINSTRUMENTED = {"el_crc16.c"}
FIGURES = ROOT / "build" / "fuzz" / "figures.md"


def run_fuzzer(tmp_path: Path, name: str, sources: list[Path], corpus: str, cflags: tuple[str, ...] = (),
               includes: tuple[Path, ...] = (), args: tuple[str, ...] = ()) -> str:
    """Build fuzz target ``name`` from ``sources`` (with runtime_c/ and
    ``includes`` on the include path) and run it on a copy of
    fuzz/``corpus``: at least MIN_RUNS executions without a finding.
    Returns libFuzzer's report (stderr)."""
    if shutil.which("clang") is None:
        pytest.skip("clang is not installed")
    exe = tmp_path / name
    common = ["clang", "-g", "-O1", "-std=c99", "-Wall", "-Wextra", "-Werror", "-fno-sanitize-recover=all", *cflags,
              *(f"-I{d}" for d in (*includes, RUNTIME))]
    plain = [s for s in sources if s.name in UNINSTRUMENTED]
    objects = []
    for src in plain:  # ASan and UBSan, no coverage
        obj = tmp_path / f"{src.stem}.o"
        proc = subprocess.run([*common, "-fsanitize=address,undefined", "-c", str(src), "-o", str(obj)],
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr
        objects.append(obj)
    cmd = [*common, "-fsanitize=fuzzer,address,undefined", *(str(s) for s in sources if s not in plain),
           *map(str, objects), "-o", str(exe)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if proc.returncode != 0 and "libclang_rt.fuzzer" in proc.stderr:
        pytest.skip("clang's libFuzzer runtime is missing (Debian: libclang-rt-14-dev)")
    assert proc.returncode == 0, proc.stderr
    seeds = tmp_path / "corpus"
    shutil.copytree(FUZZ / corpus, seeds)
    run = subprocess.run([str(exe), str(seeds), f"-runs={RUNS}", "-seed=1", f"-max_total_time={MAX_SECONDS}",
                          "-rss_limit_mb=2048", "-print_final_stats=1", *args],
                         capture_output=True, text=True, timeout=MAX_SECONDS + 180, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-4000:]
    done = re.search(r"^Done (\d+) runs in (\d+) second", run.stderr, re.MULTILINE)
    assert done and int(done.group(1)) >= MIN_RUNS, run.stderr[-2000:]
    if "EASYLAB_FUZZ_RUNS" in os.environ:
        _record(name, cflags, int(done.group(1)), int(done.group(2)), run.stderr)
    return run.stderr


def _record(name: str, cflags: tuple[str, ...], runs: int, seconds: int, report: str) -> None:
    """One line of `make fuzz`'s figures: target, variant, executions,
    seconds, executions a second, coverage, findings (0: the run passed)."""
    cov = re.findall(r"cov: (\d+) ft: (\d+)", report)
    variant = " ".join(f for f in cflags if f.startswith("-D")) or "-"
    FIGURES.parent.mkdir(parents=True, exist_ok=True)
    if not FIGURES.exists():
        FIGURES.write_text("| target | variant | executions | seconds | per second | cov | ft | findings |\n"
                           "|---|---|---|---|---|---|---|---|\n")
    with FIGURES.open("a") as f:
        c, ft = cov[-1] if cov else ("?", "?")
        f.write(f"| {name} | {variant} | {runs:,} | {seconds} | {runs // max(seconds, 1):,} | {c} | {ft} | 0 |\n")
