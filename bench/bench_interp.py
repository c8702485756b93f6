"""Local execution against the host-native firmware: actor firings per second.

For cd_to_dat (613 firings of 7 actor plug-ins per activation) and
pt100_sensor (a control model: 4 firings per 10 ms activation, a chart-free
LET dispatcher with a channel), both run the same number of activations in
virtual time without a trace: the interpreter in this process
(``Engine.run``, as ``easylab run --fast`` does), the firmware as a process
(``--fast --duration``, its start-up measured with a zero duration and
subtracted). Best of several runs each. Also: the interpreter with its
interfaces library loaded (the firmware's debug and Modbus servers, as
`easylab run --debug/--modbus-*` has them, without a client: the cost of
the hooks and of copying the items in and out), and the time to build a
model's plug-ins into an empty cache, and to load them from a warm one.

Run: python bench/bench_interp.py [out_dir]  (writes out_dir/interp.json)
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CASES = {
    # model: activations timed (the same count for both)
    "cd_to_dat": 20000,
    "pt100_sensor": 100000,
}
INTERP_REPEATS = 3
NATIVE_REPEATS = 10  # a native run takes milliseconds: more runs against the noise


def _best(fn, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def _firings_per_activation(program, task_name: str) -> int:
    """Actor firings per activation of a task (external nodes excluded)."""
    task = next(t for t in program.tasks if t.name == task_name)
    total = 0
    for kind, ident in task.runs:
        if kind == "dataflow":
            df = program.dataflows[ident]
            names = {program.instances[i].name for i in df.instances}
            total += sum(n for node, n in df.repetitions.items() if node in names)
    return total


def measure(name: str, activations: int, work: Path,
            repeats: tuple[int, int] = (INTERP_REPEATS, NATIVE_REPEATS)) -> dict:
    from easylab.build import build
    from easylab.pipeline import lower_file
    from easylab.interp import Engine, PluginCache
    from easylab.interp.engine import InterfaceOptions

    program, result = lower_file(ROOT / "examples" / f"{name}.elab")
    assert program is not None, result.report()
    task = min(program.tasks, key=lambda t: t.period)  # the task the count is about
    period_us = task.period * program.tick_us
    firings = _firings_per_activation(program, task.name)

    cache_dir = work / f"cache_{name}"
    start = time.perf_counter()
    PluginCache(cache_dir).load_all(program.specs)
    cold = time.perf_counter() - start
    start = time.perf_counter()
    cache = PluginCache(cache_dir)
    cache.load_all(program.specs)
    warm = time.perf_counter() - start

    duration_us = activations * period_us

    def interpret():
        engine = Engine(program, cache)
        engine.run(duration_us)
        engine.shutdown()
        assert engine.activations[task.name] == activations
    interp_s = _best(interpret, repeats[0])

    def interpret_served():
        engine = Engine(program, cache, interfaces=InterfaceOptions())
        engine.run(duration_us)
        engine.shutdown()
        assert engine.activations[task.name] == activations
    served_s = _best(interpret_served, repeats[0])

    exe = build(program, "host", work / f"fw_{name}", release=True).executable

    def native(duration: str):
        return lambda: subprocess.run([str(exe), "--fast", "--duration", duration], check=True)
    startup = _best(native("0us"), repeats[1])
    native_s = max(_best(native(f"{duration_us}us"), repeats[1]) - startup, 1e-9)
    return {
        "model": name, "task": task.name, "activations": activations, "firings_per_activation": firings,
        "interp_s": interp_s, "native_s": native_s, "native_startup_s": startup,
        "interp_firings_per_s": activations * firings / interp_s,
        "native_firings_per_s": activations * firings / native_s,
        "interp_us_per_activation": interp_s / activations * 1e6,
        "native_us_per_activation": native_s / activations * 1e6,
        "ratio": interp_s / native_s,
        "interp_served_s": served_s, "served_us_per_activation": served_s / activations * 1e6,
        "served_ratio": served_s / interp_s,
        "plugins": len(program.specs), "plugins_cold_build_s": cold, "plugins_warm_load_s": warm,
    }


def main(out_dir, tiny: bool = False) -> dict:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        results = [measure(name, 20 if tiny else n, Path(tmp), (1, 1) if tiny else (INTERP_REPEATS, NATIVE_REPEATS))
                   for name, n in CASES.items()]
    (out / "interp.json").write_text(json.dumps({"cases": results, "python": sys.version.split()[0],
                                                  "cpus": os.cpu_count()}, indent=2))
    print(f"{'model':<14} {'activations':>11} {'firings/act':>11} {'interp firings/s':>17} "
          f"{'native firings/s':>17} {'interp us/act':>13} {'native us/act':>13} {'ratio':>7}")
    for r in results:
        print(f"{r['model']:<14} {r['activations']:>11} {r['firings_per_activation']:>11} "
              f"{r['interp_firings_per_s']:>17,.0f} {r['native_firings_per_s']:>17,.0f} "
              f"{r['interp_us_per_activation']:>13.1f} {r['native_us_per_activation']:>13.2f} {r['ratio']:>7.0f}")
    print()
    for r in results:
        print(f"{r['model']}: with its interfaces served {r['served_us_per_activation']:.1f} us per activation, "
              f"{r['served_ratio']:.2f} times the interpreter alone")
    for r in results:
        print(f"{r['model']}: {r['plugins']} plug-ins built in {r['plugins_cold_build_s']:.2f} s (empty cache), "
              f"loaded in {r['plugins_warm_load_s'] * 1e3:.0f} ms (warm cache)")
    return {"cases": results}


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ROOT / "bench" / "results")
