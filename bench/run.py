"""`make bench`: run every benchmark, results in bench/results/ (JSON, one
file per benchmark). The figures in docs/benchmarks.md come from here.

Timing goals live here, not in the tests: the machines are noisy, so the
benchmarks report instruction counts (callgrind), ratios and sizes where
they can, and wall-clock seconds only where nothing else measures it.
"""

from __future__ import annotations

import importlib.util
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
# In the order they build on each other; each has main(out_dir).
BENCHMARKS = ["bench_frontend", "bench_sdf", "bench_codegen", "bench_interp", "bench_debug", "bench_debug_web",
              "bench_service", "bench_avr", "bench_pic18", "bench_remote", "bench_distribution", "bench_multicore", "bench_lsp"]


def _load(name: str):
    spec = importlib.util.spec_from_file_location(name, HERE / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main(argv: list[str]) -> int:
    """``run.py [--tiny] [OUT_DIR [BENCHMARK ...]]``: --tiny runs each at a
    tiny size (the test suite does, so that no benchmark rots)."""
    tiny = "--tiny" in argv
    argv = [a for a in argv if a != "--tiny"]
    out = Path(argv[0]) if argv else HERE / "results"
    wanted = argv[1:] or BENCHMARKS
    failed = []
    for name in wanted:
        if not (HERE / f"{name}.py").is_file():
            continue
        print(f"\n=== {name}")
        start = time.perf_counter()
        try:
            _load(name).main(out, tiny=tiny)
        except SystemExit as err:
            if err.code not in (None, 0):
                print(f"{name}: {err}", file=sys.stderr)
                failed.append(name)
        except Exception as err:  # a broken benchmark: report it, run the others
            print(f"{name}: {type(err).__name__}: {err}", file=sys.stderr)
            failed.append(name)
        print(f"({name}: {time.perf_counter() - start:.1f} s)")
    print(f"\nresults in {out}/")
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
