"""Logical execution time on the host board (data/let_*.elab).

Task `work` (period 10 ms, offset 2 ms, deadline 5 ms) counts its releases
and copies the var `input`; task `fast` (1 ms) copies what `work` published.
The expected trace is worked out by hand from docs/ir.md:

- tick = gcd(10, 2, 5, 1) ms = 1 ms; every tick is an instant (task fast);
- `work` is released at 2, 12, 22, ... ms and publishes at 7, 17, 27, ...;
- `fast` released at t sees what was published at t (outputs first) and
  publishes at t + 1 ms;
- input is written by the stimulus at the first instant at or after its
  time (3.5 ms -> 4 ms; 25 ms -> 25 ms), before that instant's releases.

let_busy.elab spins in `work` (a volatile loop, well below the deadline in
real time): the trace must be byte-identical, in virtual and in real time.
"""

from __future__ import annotations

import resource
import subprocess
from concurrent.futures import ThreadPoolExecutor

import pytest

from native_testlib import DATA, build, run

EXPECTED_50MS = """\
time_us,input,count,echo,seen,seen_input
0,0,0,0,0,0
4000,7,0,0,0,0
5000,7,0,0,0,7
7000,7,1,0,0,7
8000,7,1,0,1,7
17000,7,2,7,1,7
18000,7,2,7,2,7
25000,9,2,7,2,7
26000,9,2,7,2,9
27000,9,3,7,2,9
28000,9,3,7,3,9
37000,9,4,9,3,9
38000,9,4,9,4,9
47000,9,5,9,4,9
48000,9,5,9,5,9
"""


@pytest.fixture(scope="module")
def programs(tmp_path_factory):
    d = tmp_path_factory.mktemp("let")
    with ThreadPoolExecutor(max_workers=2) as pool:
        exes = pool.map(lambda name: build(DATA / f"{name}.elab", d / name), ("let_timing", "let_busy"))
        return dict(zip(("plain", "busy"), exes))


def test_outputs_appear_at_the_deadline(programs, tmp_path):
    r = run(programs["plain"], tmp_path / "t.csv", duration="50ms", stimulus=DATA / "let.stimulus.csv")
    assert r.trace_text == EXPECTED_50MS
    count = r.trace.changes("count")
    assert [t for t, _ in count] == [0, 7000, 17000, 27000, 37000, 47000]
    # Released 2 ms after the period starts, visible 5 ms after the release.
    assert all((t - 2000) % 10000 == 5000 for t, _ in count[1:])


def test_busy_task_leaves_the_trace_identical(programs, tmp_path):
    stim = DATA / "let.stimulus.csv"
    fast_plain = run(programs["plain"], tmp_path / "fp.csv", duration="50ms", stimulus=stim).trace_text
    fast_busy = run(programs["busy"], tmp_path / "fb.csv", duration="50ms", stimulus=stim).trace_text
    assert fast_plain == fast_busy == EXPECTED_50MS


def test_the_busy_loop_really_spins_below_the_deadline(programs, tmp_path):
    """100 releases of `work` in virtual time: at least 10^8 volatile
    iterations (well over 10 ms of CPU on any machine), yet under 5 ms of
    CPU each (CPU time of the child: the machine's load does not count)."""
    def cpu(exe) -> float:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([str(exe), "--fast", "--duration", "1s", "--trace", str(tmp_path / "w.csv")], check=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        return (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)

    plain, busy = cpu(programs["plain"]), cpu(programs["busy"])
    assert busy - plain > 0.010
    assert busy / 100 < 0.005


@pytest.mark.parametrize("which", ["plain", "busy"])
def test_real_time_trace_is_the_virtual_one(programs, tmp_path, which):
    """Without --fast the run sleeps to each tick (50 ms); lateness, if the
    machine is loaded, is reported on stderr but never changes values."""
    stim = DATA / "let.stimulus.csv"
    r = run(programs[which], tmp_path / "rt.csv", duration="50ms", stimulus=stim, fast=False, clean=False)
    assert r.proc.returncode == 0, r.proc.stderr
    assert r.proc.stderr == "" or r.proc.stderr.count("\n") == 1 and "overruns:" in r.proc.stderr, r.proc.stderr
    assert r.trace_text == EXPECTED_50MS
