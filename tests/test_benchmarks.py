"""Every benchmark of `make bench` runs here at a tiny size, so that none
rots unnoticed (the figures themselves are goals of `make bench`, not of
the tests: docs/benchmarks.md)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = {"bench_frontend": "frontend.json", "bench_sdf": "sdf.json", "bench_codegen": "codegen.json",
           "bench_interp": "interp.json", "bench_debug": "debug.json", "bench_debug_web": "debug_web.json",
           "bench_service": "service.json",
           "bench_avr": "avr.json", "bench_pic18": "pic18.json", "bench_remote": "remote.json",
           "bench_distribution": "distribution.json", "bench_multicore": "multicore.json",
           "bench_lsp": "lsp.json"}


def test_every_benchmark_is_listed_here_and_in_run_py():
    sys.path.insert(0, str(ROOT / "bench"))
    try:
        import run
    finally:
        sys.path.pop(0)
    on_disk = {p.stem for p in (ROOT / "bench").glob("bench_*.py")}
    assert on_disk == set(RESULTS) == set(run.BENCHMARKS)


# Benchmarks whose tiny run still keeps a deadline against the wall clock
# (remote execution at 1 Mbaud): `make test` runs them with the realtime tests.
ON_THE_WALL_CLOCK = {"bench_remote"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=[pytest.mark.realtime] if n in ON_THE_WALL_CLOCK else [])
                                  for n in sorted(RESULTS)])
def test_the_benchmark_runs_at_a_tiny_size(name, tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "bench" / "run.py"), "--tiny", str(tmp_path), name],
                          capture_output=True, text=True, timeout=900, cwd=ROOT, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    figures = json.loads((tmp_path / RESULTS[name]).read_text())
    assert figures
