"""Benchmark of multi-core host builds (docs/multicore.md).

The camera line-following example (examples/vision_line/), built for the
host board with --cores 1 and --cores 2 and run in real time for
VISION_PERIODS periods of its task, in turns, REPEATS times: each run's
overruns (the program's own count of activations that ended a tick or
more after their deadline), the wall time's minimum and median and the
speedup of 2 cores over 1, whether one core misses the period and two keep
it; then the same
programs in virtual time (``--fast``), where nothing waits for the clock:
the time of one activation on each core count against the prediction of
``easylab analyze --cores 2`` (from the example's declared costs).

A synthetic balanced graph (a source, BRANCHES independent branches of
xorshift work, a join) and a tiny model (examples/blink.elab), each built
for the host board with --cores 1 and --cores 2 and run in virtual time
(``--fast``) in turns, REPEATS times: the minimum and median wall time,
the speedup of 2 cores over 1, and the time of one activation on 2 cores
against the prediction of ``easylab analyze --cores 2 --profile``.
Writes ``<out_dir>/multicore.json``.

    python bench/bench_multicore.py [out_dir]     (default: bench/results)
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VISION = ROOT / "examples" / "vision_line" / "vision_line.elab"
VISION_PERIODS = 2000
BRANCHES = 4
WORK = 100_000  # xorshift rounds per branch firing (~150 us)
REPEATS = 7
ACTIVATIONS = 1000  # one per ms of virtual time
# docs/benchmarks.md: the goals of issue "Multicore".
GOAL_SPEEDUP = 1.7
GOAL_PREDICTION = 0.15
GOAL_TINY_RATIO = 1.1

ACTORS = """\
model balanced
actor type Src() {
    out y: uint32
    state n: uint32
    step {{ n = n + 1u; y = n; }}
}
actor type Work(seed: uint32, rounds: uint32) {
    in  x: uint32
    out y: uint32
    cost COST us
    step {{
        uint32_t i;
        uint32_t a = x ^ seed;
        for (i = 0u; i < rounds; i++) { a ^= a << 13; a ^= a >> 17; a ^= a << 5; }
        y = a;
    }}
}
actor type Pair() {
    in  a: uint32
    in  b: uint32
    out y: uint32
    step {{ y = a * 31u + b; }}
}
var out: uint32
"""


def balanced_model(branches: int, work: int, cost_us: int) -> str:
    """Src -> `branches` Work actors (a power of 2) -> a tree of Pairs -> out."""
    instances = ["    s = Src()"] + [f"    w{i} = Work(seed = {i + 1}, rounds = {work})" for i in range(branches)]
    names = [f"w{i}" for i in range(branches)]
    edges = [f"    s.y -> {n}.x" for n in names]
    level = 0
    while len(names) > 1:
        joined = []
        for k in range(0, len(names), 2):
            pair = f"p{level}_{k // 2}"
            instances.append(f"    {pair} = Pair()")
            edges += [f"    {names[k]}.y -> {pair}.a", f"    {names[k + 1]}.y -> {pair}.b"]
            joined.append(pair)
        names, level = joined, level + 1
    edges.append(f"    {names[0]}.y -> out")
    return "\n".join([ACTORS.replace("COST", str(cost_us)), "dataflow G {", *instances, *edges, "}",
                      "task t period 1 ms { run G }", ""])


# The machine's own parallelism, measured beside the figures: the same
# busy loop on one thread, then on two at once.
CONTROL = r"""
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
static volatile uint32_t sink[2];
static void *work(void *arg)
{
    uint32_t x = (uint32_t)(uintptr_t)arg + 1u;
    long i, n = atol(getenv("ROUNDS"));
    for (i = 0; i < n; i++) { x ^= x << 13; x ^= x >> 17; x ^= x << 5; }
    sink[(uintptr_t)arg] = x;
    return NULL;
}
int main(int argc, char **argv)
{
    pthread_t t[2];
    int i, n = argc > 1 ? 2 : 1;
    (void)argv;
    for (i = 0; i < n; i++) { pthread_create(&t[i], NULL, work, (void *)(uintptr_t)i); }
    for (i = 0; i < n; i++) { pthread_join(t[i], NULL); }
    return 0;
}
"""


def machine_parallelism(work_dir: Path, rounds: int, repeats: int) -> float:
    """Twice one thread's time over two threads' time: 2.0 on two free
    cores, 1.0 when the machine gives the process one core's worth."""
    source, exe = work_dir / "control.c", work_dir / "control"
    source.write_text(CONTROL)
    subprocess.run(["gcc", "-O2", "-pthread", "-o", str(exe), str(source)], check=True)
    env = {**os.environ, "ROUNDS": str(rounds)}
    one, two = [], []
    for _ in range(repeats):
        for args, times in (([], one), (["2"], two)):
            start = time.perf_counter()
            subprocess.run([str(exe), *args], check=True, env=env)
            times.append(time.perf_counter() - start)
    return 2 * min(one) / min(two)


def easylab(*args: str) -> str:
    proc = subprocess.run([sys.executable, "-m", "easylab", *args], capture_output=True, text=True, cwd=ROOT,
                          stdin=subprocess.DEVNULL)
    if proc.returncode != 0:
        raise SystemExit(f"easylab {' '.join(args)} failed:\n{proc.stdout}{proc.stderr}")
    return proc.stdout


def build(model: Path, out: Path, cores: int) -> tuple[Path, str]:
    printed = easylab("build", str(model), "--board", "host", "--cores", str(cores), "-o", str(out))
    return Path(printed.strip().splitlines()[-1]), printed


def timed_runs(programs: dict[int, Path], args: list[str], repeats: int) -> dict[int, list[float]]:
    """Wall seconds of each program, run in turns (1, 2, 1, 2, ...) so that
    the machine's load falls on both alike."""
    times: dict[int, list[float]] = {n: [] for n in programs}
    for _ in range(repeats):
        for n, exe in programs.items():
            start = time.perf_counter()
            subprocess.run([str(exe), *args], check=True, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL)
            times[n].append(time.perf_counter() - start)
    return times


def figures(times: dict[int, list[float]]) -> dict:
    out = {f"cores{n}": {"min_s": min(t), "median_s": statistics.median(t)} for n, t in times.items()}
    out["speedup_min"] = min(times[1]) / min(times[2])
    out["speedup_median"] = statistics.median(times[1]) / statistics.median(times[2])
    return out


def overruns_of(stderr: str) -> int:
    """The overruns a host program reports at its end (``PROG: overruns:
    TASK N ...``; nothing when there were none), summed over its tasks."""
    for line in stderr.splitlines():
        if ": overruns:" in line:
            words = line.split(": overruns:", 1)[1].split()
            return sum(int(n) for n in words[1::2])
    return 0


def task_period_us(model: Path) -> int:
    """The period of the model's first task, in microseconds (its IR)."""
    from easylab.pipeline import lower_file
    program, result = lower_file(str(model))
    if program is None:
        raise SystemExit(result.report())
    return program.tasks[0].period * program.tick_us


def real_time_runs(programs: dict[int, Path], duration_us: int, repeats: int) -> tuple[dict, dict]:
    """Real-time runs in turns: (cores -> wall seconds, cores -> overruns), one entry per run."""
    times: dict[int, list[float]] = {n: [] for n in programs}
    overruns: dict[int, list[int]] = {n: [] for n in programs}
    for _ in range(repeats):
        for n, exe in programs.items():
            start = time.perf_counter()
            proc = subprocess.run([str(exe), "--duration", f"{duration_us}us"], check=True, capture_output=True,
                                  text=True, stdin=subprocess.DEVNULL)
            times[n].append(time.perf_counter() - start)
            overruns[n].append(overruns_of(proc.stderr))
    return times, overruns


def vision_line(work_dir: Path, periods: int, repeats: int) -> dict:
    """examples/vision_line on 1 and 2 cores: real time (overruns, wall
    time) and virtual time (one activation against the prediction)."""
    flow = json.loads(easylab("analyze", str(VISION), "--cores", "2", "--json"))["dataflows"][0]
    period_us = task_period_us(VISION)
    with ThreadPoolExecutor(max_workers=2) as pool:  # two compilers at once: the tiny run stays short
        built = dict(zip((1, 2), pool.map(lambda n: build(VISION, work_dir / f"vision{n}", n), (1, 2))))
    programs, notes = {n: exe for n, (exe, _) in built.items()}, {n: note for n, (_, note) in built.items()}
    times, overruns = real_time_runs(programs, periods * period_us, repeats)
    real = figures(times)
    fast = figures(timed_runs(programs, ["--fast", "--duration", f"{periods * period_us}us"], repeats))
    per_activation = {n: fast[f"cores{n}"]["min_s"] * 1e9 / periods for n in (1, 2)}
    return {
        "periods": periods, "period_us": period_us, "parallel": "on 2 cores" in notes[2],
        "real_time": real, "overruns_cores1": overruns[1], "overruns_cores2": overruns[2],
        "one_core_misses": min(overruns[1]) > 0,
        "two_cores_keep": statistics.median(overruns[2]) == 0,
        "virtual_time": fast,
        "activation_ns_cores1": round(per_activation[1]), "activation_ns_cores2": round(per_activation[2]),
        "predicted_ns_cores1": flow["sequential_ns"], "predicted_ns_cores2": flow["predicted_ns"],
        "prediction_error": (per_activation[2] - flow["predicted_ns"]) / flow["predicted_ns"],
    }


def main(out_dir: str | Path = "bench/results", tiny: bool = False) -> dict:
    """Run the benchmark, print its figures, write ``out_dir/multicore.json``."""
    repeats, activations, work = (2, 50, 2_000) if tiny else (REPEATS, ACTIVATIONS, WORK)
    with tempfile.TemporaryDirectory(prefix="bench-multicore-") as tmp:
        work_dir = Path(tmp)
        model = work_dir / "balanced.elab"
        model.write_text(balanced_model(BRANCHES, work, max(work // 700, 1)), encoding="utf-8")
        analysis = json.loads(easylab("analyze", str(model), "--cores", "2", "--profile", "--json",
                                      "--duration", f"{min(activations, 200)}ms"))
        flow = analysis["dataflows"][0]
        programs, notes = {}, {}
        for n in (1, 2):
            programs[n], notes[n] = build(model, work_dir / f"c{n}", n)
        args = ["--fast", "--duration", f"{activations}ms"]
        balanced = figures(timed_runs(programs, args, repeats))
        measured_ns = balanced["cores2"]["min_s"] * 1e9 / activations
        balanced.update({
            "branches": BRANCHES, "rounds": work, "activations": activations,
            "one_core_ns_profiled": flow["sequential_ns"], "predicted_ns": flow["predicted_ns"],
            "measured_ns_per_activation_2_cores": round(measured_ns),
            "prediction_error": (measured_ns - flow["predicted_ns"]) / flow["predicted_ns"],
            "parallel": "on 2 cores" in notes[2],
        })
        blink = ROOT / "examples" / "blink.elab"
        tiny_programs = {n: build(blink, work_dir / f"blink{n}", n)[0] for n in (1, 2)}
        tiny_note = build(blink, work_dir / "blink_note", 2)[1]
        small = figures(timed_runs(tiny_programs, ["--fast", "--duration", "3s" if not tiny else "100ms",
                                                   "--stimulus", str(ROOT / "examples" / "blink.stimulus.csv")],
                                   repeats))
        small["ratio_2_over_1_median"] = 1 / small["speedup_median"]
        small["single_core_chosen"] = "a single-core build" in tiny_note
        vision = vision_line(work_dir, 20 if tiny else VISION_PERIODS, repeats)
        parallelism = machine_parallelism(work_dir, 2_000 * work, repeats)
    report = {"benchmark": "multicore", "machine_cores": os.cpu_count(), "machine_parallelism": parallelism,
              "load_average": os.getloadavg(), "vision_line": vision, "balanced": balanced, "tiny": small,
              "goals": {"speedup": GOAL_SPEEDUP, "prediction_error": GOAL_PREDICTION, "tiny_ratio": GOAL_TINY_RATIO}}
    real, fast = vision["real_time"], vision["virtual_time"]
    print(f"vision_line ({vision['periods']} periods of {vision['period_us']} us in real time): overruns "
          f"{vision['overruns_cores1']} on 1 core, {vision['overruns_cores2']} on 2; wall time min "
          f"{real['cores1']['min_s']:.3f} s / {real['cores2']['min_s']:.3f} s, speedup {real['speedup_min']:.2f} "
          f"(min), {real['speedup_median']:.2f} (median); one core misses the period: {vision['one_core_misses']}, "
          f"two keep it: {vision['two_cores_keep']}")
    print(f"vision_line in virtual time: one activation {vision['activation_ns_cores1'] / 1000:.0f} us on 1 core, "
          f"{vision['activation_ns_cores2'] / 1000:.0f} us on 2 (predicted {vision['predicted_ns_cores1'] / 1000:.0f}"
          f" / {vision['predicted_ns_cores2'] / 1000:.0f} us: error {vision['prediction_error']:+.0%}, goal within "
          f"{GOAL_PREDICTION:.0%}); speedup {fast['speedup_min']:.2f} (min), {fast['speedup_median']:.2f} (median), "
          f"goal {GOAL_SPEEDUP}")
    print(f"balanced graph ({BRANCHES} branches of {work} rounds, {activations} activations): "
          f"1 core min {balanced['cores1']['min_s']:.3f} s, 2 cores min {balanced['cores2']['min_s']:.3f} s; "
          f"speedup {balanced['speedup_min']:.2f} (min), {balanced['speedup_median']:.2f} (median), "
          f"goal {GOAL_SPEEDUP}")
    print(f"one activation on 2 cores: {measured_ns / 1000:.1f} us measured, {flow['predicted_ns'] / 1000:.1f} us "
          f"predicted: error {balanced['prediction_error']:+.0%} (goal within {GOAL_PREDICTION:.0%})")
    print(f"tiny model (blink): --cores 2 / --cores 1 = {small['ratio_2_over_1_median']:.2f} (median; goal at most "
          f"{GOAL_TINY_RATIO}); single core chosen: {small['single_core_chosen']}")
    print(f"load average {report['load_average'][0]:.2f} on {report['machine_cores']} cores; two busy threads run "
          f"{parallelism:.2f} times as much as one (2.00: two free cores)")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "multicore.json").write_text(json.dumps(report, indent=2) + "\n")
    return report


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "bench/results")
