"""Benchmark of the SDF library on random consistent graphs.

Generates seeded random graphs of 100, 1,000 and 10,000 actors, chain-like
and tree-like, with back edges whose delay covers one iteration, and times
each analysis step: repetition vector, deadlock check, the single-appearance
schedule (APGAN/RPMC + DPPO) and the flat minimum-buffer schedule.  Prints a
table and writes ``<out_dir>/sdf.json``.

    python bench/bench_sdf.py [out_dir]     (default: bench/results)
"""

from __future__ import annotations

import json
import math
import platform
import random
import sys
import time
from pathlib import Path

if __package__ in (None, ""):  # a script from a source checkout
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from source_checkout import make_easylab_importable

    make_easylab_importable()

from easylab.analysis.sdf import SdfGraph, analyze, check_deadlock, repetition_vector

SIZES = (100, 1_000, 10_000)
# docs/benchmarks.md: the 10,000-actor tree's single-appearance schedule in
# under this many seconds (with the same buffer totals or better:
# tests/sdf/test_sdf_bench_graphs.py keeps those of the smaller graphs).
GOAL_SAS_S = {"tree-10000": 2.0}
SHAPES = ("chain", "tree", "bigq")
SEED = 20240601
# Firing counts per actor come from these, so every edge's rates stay small
# (at most 12 before scaling) while counts along a path vary.
COUNTS = (1, 2, 3, 4, 6, 8, 12)
FLAT_FIRINGS_LIMIT = 1_000_000


def _walking_counts(actors: int, rng: random.Random) -> list[int]:
    """Large firing counts whose neighbours differ by a factor of 2, 3 or 5:
    a random walk over the exponents of 2**a * 3**b * 5**c (up to ~10**7)."""
    limits = (8, 6, 4)
    exponents = [rng.randint(0, limit) for limit in limits]
    counts = []
    for _ in range(actors):
        which = rng.randrange(3)
        exponents[which] = min(limits[which], max(0, exponents[which] + rng.choice((-1, 1))))
        counts.append(2 ** exponents[0] * 3 ** exponents[1] * 5 ** exponents[2])
    return counts


def random_graph(actors: int, shape: str, rng: random.Random) -> SdfGraph:
    """A consistent, live graph: a chain or a random tree of forward edges,
    a few extra forward edges, and back edges with a whole iteration's
    worth of initial tokens.  Shape ``bigq`` is a chain with large counts."""
    if shape == "bigq":
        counts = _walking_counts(actors, rng)
    else:
        counts = [rng.choice(COUNTS) for _ in range(actors)]
    graph = SdfGraph([f"n{i}" for i in range(actors)], name=f"{shape}-{actors}")

    def connect(u: int, v: int, delay_for_traffic: bool) -> None:
        g = math.gcd(counts[u], counts[v])
        prod, cons = counts[v] // g, counts[u] // g
        scale = rng.randint(1, max(1, 12 // max(prod, cons))) if max(prod, cons) <= 12 else 1
        prod, cons = prod * scale, cons * scale
        delay = counts[v] * cons + rng.randint(0, 3) if delay_for_traffic else rng.choice((0, 0, 0, 1))
        graph.add_edge(f"n{u}", f"n{v}", prod, cons, delay)

    for v in range(1, actors):
        u = rng.randint(max(0, v - 50), v - 1) if shape == "tree" else v - 1
        connect(u, v, False)
    for _ in range(actors // 20):
        u = rng.randrange(actors - 1)
        connect(u, rng.randint(u + 1, min(actors - 1, u + 10)), False)
    for _ in range(actors // 20):
        u = rng.randrange(1, actors)
        connect(u, rng.randint(max(0, u - 10), u - 1), True)
    return graph


def measure(graph: SdfGraph) -> dict:
    """Time each analysis step on ``graph``; return the figures."""
    row = {"graph": graph.name, "actors": len(graph.actors), "edges": len(graph.edges)}
    start = time.perf_counter()
    repetitions = repetition_vector(graph)
    row["repetitions_s"] = time.perf_counter() - start
    row["firings"] = sum(repetitions.values())
    start = time.perf_counter()
    check_deadlock(graph, repetitions)
    row["deadlock_s"] = time.perf_counter() - start
    start, cpu = time.perf_counter(), time.process_time()
    sas = analyze(graph, "sas")
    row["sas_s"] = time.perf_counter() - start
    row["sas_cpu_s"] = time.process_time() - cpu  # less moved by other processes than the wall clock
    row.update(
        sas_method=sas.method,
        sas_total=sas.buffer_total,
        flat_sas_total=sas.flat_sas_total,
        sas_lower_bound=sas.sas_lower_bound,
        edge_lower_bound=sas.edge_lower_bound,
        min_buffer_s=None,
        min_buffer_total=None,
        min_buffer_gap=None,
        min_buffer_optimal=None,
    )
    if row["firings"] > FLAT_FIRINGS_LIMIT:
        # A flat schedule of millions of firings is no code to generate.
        row["min_buffer_note"] = f"skipped: {row['firings']} firings per iteration"
        return row
    start = time.perf_counter()
    flat = analyze(graph, "min-buffer")
    row["min_buffer_s"] = time.perf_counter() - start
    row.update(
        min_buffer_total=flat.buffer_total,
        min_buffer_gap=flat.edge_bound_gap,
        min_buffer_optimal=flat.optimal,
        min_buffer_method=flat.method,
    )
    return row


def _short(value) -> str:
    """Integers above 8 digits in scientific notation, to keep the table narrow."""
    if value is None:
        return "-"
    return f"{value:.2e}" if value >= 10**8 else str(value)


def main(out_dir: str | Path = "bench/results", tiny: bool = False, sizes=SIZES, seed: int = SEED) -> list[dict]:
    """Run the benchmark, print a table, write ``out_dir/sdf.json``."""
    if tiny:
        sizes = sizes[:1]
    rng = random.Random(seed)
    rows = [measure(random_graph(size, shape, rng)) for size in sizes for shape in SHAPES]
    header = (
        f"{'graph':<12} {'actors':>6} {'edges':>6} {'firings':>8} {'reps s':>7} {'dead s':>7} "
        f"{'SAS s':>7} {'minbuf s':>8} {'flatSAS':>9} {'SAS':>8} {'SAS lb':>8} {'minbuf':>7} {'edge lb':>7}"
    )
    print(header)
    print("-" * len(header))
    def show(value, width, digits=None):
        if value is None:
            return "-".rjust(width)
        return (f"{value:.{digits}f}" if digits else f"{value}").rjust(width)

    for r in rows:
        print(
            f"{r['graph']:<12} {r['actors']:>6} {r['edges']:>6} {_short(r['firings']):>8} "
            f"{show(r['repetitions_s'], 7, 3)} {show(r['deadlock_s'], 7, 3)} {show(r['sas_s'], 7, 3)} "
            f"{show(r['min_buffer_s'], 8, 3)} {_short(r['flat_sas_total']):>9} {_short(r['sas_total']):>8} "
            f"{_short(r['sas_lower_bound']):>8} {show(r['min_buffer_total'], 7)} "
            f"{_short(r['edge_lower_bound']):>7}"
        )
    for r in rows:
        if r["graph"] in GOAL_SAS_S:
            goal = GOAL_SAS_S[r["graph"]]
            r["sas_goal_s"] = goal
            print(f"{r['graph']}: single-appearance schedule in {r['sas_s']:.2f} s ({r['sas_cpu_s']:.2f} s of CPU), "
                  f"goal under {goal} s: {'met' if r['sas_s'] < goal else 'MISSED'}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    report = {
        "benchmark": "sdf",
        "seed": seed,
        "python": platform.python_version(),
        "note": "times in seconds; the SAS and min-buffer times each include the repetition "
                "vector, the deadlock check and the verification by simulation",
        "results": rows,
    }
    (out / "sdf.json").write_text(json.dumps(report, indent=2) + "\n")
    return rows


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "bench/results")
