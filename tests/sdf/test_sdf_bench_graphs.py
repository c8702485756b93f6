"""The schedules' buffer totals on the benchmark's own graphs
(bench/bench_sdf.py, its seed) do not get worse: work on the speed of the
schedulers must keep, or improve, what they find. The 10,000-actor graphs
are `make bench`'s (docs/benchmarks.md); the 100- and 1,000-actor ones run
here in a few seconds."""

from __future__ import annotations

import importlib.util
import random
from pathlib import Path

import pytest

from easylab.analysis.sdf import analyze

# graph: (single-appearance total, minimum-buffer total or None when skipped)
TOTALS = {
    "chain-100": (1459, 1106), "tree-100": (1434, 1013), "bigq-100": (1517574, None),
    "chain-1000": (13858, 10941), "tree-1000": (14021, 9929), "bigq-1000": (120485287, None),
}


@pytest.fixture(scope="module")
def graphs():
    path = Path(__file__).resolve().parents[2] / "bench" / "bench_sdf.py"
    spec = importlib.util.spec_from_file_location("bench_sdf", path)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    rng = random.Random(bench.SEED)  # the benchmark's sequence of graphs, up to 1,000 actors
    return {g.name: g for g in (bench.random_graph(size, shape, rng)
                                for size in bench.SIZES[:2] for shape in bench.SHAPES)}


@pytest.mark.parametrize("name", list(TOTALS))
def test_buffer_totals_do_not_get_worse(graphs, name):
    sas, min_buffer = TOTALS[name]
    assert analyze(graphs[name], "sas").buffer_total <= sas
    if min_buffer is not None:
        assert analyze(graphs[name], "min-buffer").buffer_total <= min_buffer
