"""Local execution against the host-native firmware: actor firings per second.

For cd_to_dat (613 firings of 7 actor plug-ins per activation) and
pt100_sensor (a control model: 4 firings per 10 ms activation, a chart-free
LET dispatcher with a channel), both run the same number of activations in
virtual time without a trace: the interpreter in this process
(``Engine.run``, as ``easylab run --fast`` does), the firmware as a process
(``--fast --duration``, its start-up measured with a zero duration and
subtracted). Best of several runs each; the goal is a ratio of at most
``GOAL_RATIO`` (docs/benchmarks.md). Also, on a tenth of the activations:
the interpreter writing a CSV trace (every instant through the engine's
step in Python), and with its interfaces library loaded (the firmware's
debug and Modbus servers, as `easylab run --debug/--modbus-*` has them,
without a client: the hooks at each instant); and the time to build a
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
    "pt100_sensor": 1000000,
}
GOAL_RATIO = 20  # interpreter / native, at most
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
    from easylab.interp.trace import TraceWriter, columns_of

    program, result = lower_file(ROOT / "examples" / f"{name}.elab")
    assert program is not None, result.report()
    task = min(program.tasks, key=lambda t: t.period)  # the task the count is about
    period_us = task.period * program.tick_us
    firings = _firings_per_activation(program, task.name)

    cache_dir = work / f"cache_{name}"
    start = time.perf_counter()
    cache = PluginCache(cache_dir)
    cache.load_all(program.specs)
    cache.runner  # noqa: B018 - the interpreter's runner, built like a plug-in
    cold = time.perf_counter() - start
    start = time.perf_counter()
    cache = PluginCache(cache_dir)
    cache.load_all(program.specs)
    cache.runner  # noqa: B018
    warm = time.perf_counter() - start

    duration_us = activations * period_us

    native_instants = []

    def interpret():
        engine = Engine(program, cache)
        engine.run(duration_us)
        engine.shutdown()
        assert engine.activations[task.name] == activations
        native_instants.append(engine.native_instants)
    interp_s = _best(interpret, repeats[0])

    few = max(1, activations // 10)

    def interpret_traced():
        trace = TraceWriter(str(work / f"{name}.csv"), program, columns_of(program))
        engine = Engine(program, cache, trace=trace)
        engine.run(few * period_us)
        engine.shutdown()
        assert engine.activations[task.name] == few
    traced_s = _best(interpret_traced, repeats[0])

    def interpret_served():
        engine = Engine(program, cache, interfaces=InterfaceOptions())
        engine.run(few * period_us)
        engine.shutdown()
        assert engine.activations[task.name] == few
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
        "ratio": interp_s / native_s, "goal_ratio": GOAL_RATIO,
        "native_instants": native_instants[-1],  # of the interpreter's instants, those in the runner alone
        "traced_us_per_activation": traced_s / few * 1e6,
        "served_us_per_activation": served_s / few * 1e6,
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
          f"{'native firings/s':>17} {'interp us/act':>13} {'native us/act':>13} {'ratio':>7} {'goal':>5}")
    for r in results:
        print(f"{r['model']:<14} {r['activations']:>11} {r['firings_per_activation']:>11} "
              f"{r['interp_firings_per_s']:>17,.0f} {r['native_firings_per_s']:>17,.0f} "
              f"{r['interp_us_per_activation']:>13.2f} {r['native_us_per_activation']:>13.3f} {r['ratio']:>7.1f} "
              f"{'met' if r['ratio'] <= GOAL_RATIO else 'MISSED':>5}")
    print()
    for r in results:
        print(f"{r['model']}: {r['native_instants']} instants in the runner alone; with a CSV trace "
              f"{r['traced_us_per_activation']:.1f} us per activation, with its interfaces served "
              f"{r['served_us_per_activation']:.1f} us")
    for r in results:
        print(f"{r['model']}: {r['plugins']} plug-ins and the runner built in {r['plugins_cold_build_s']:.2f} s "
              f"(empty cache), "
              f"loaded in {r['plugins_warm_load_s'] * 1e3:.0f} ms (warm cache)")
    return {"cases": results}


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ROOT / "bench" / "results")
