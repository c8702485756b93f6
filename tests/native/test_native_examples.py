"""Every example builds for the host board with ASan and UBSan, runs in
virtual time against its stimulus in data/ with exit status 0 and nothing
on stderr, and generates the same files every time."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from native_testlib import DATA, EXAMPLE_NAMES, EXAMPLES, SANITIZE, cli


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_example_runs_clean_under_sanitizers(name, example_runs):
    r = example_runs(name)  # asserts exit status 0 and an empty stderr
    trace = r.trace
    assert trace.rows, "no instant traced"
    assert (DATA / f"{name}.stimulus.csv").exists(), f"data/{name}.stimulus.csv: give the example a stimulus"


def test_blink_follows_half_period(example_runs):
    """data/blink.stimulus.csv: half_period 10 at 0 ms, 14 from 100 ms, 20
    from 250 ms (within its declared range 10..5000, which a stimulus must
    keep). SquareWave toggles at its first firing and then every
    half_period firings (its count restarts when it reaches half_period);
    the task runs every 1 ms and publishes 1 ms after each release."""
    t = example_runs("blink").trace
    changes = [time for time, _ in t.changes("led.level")][1:]
    # Firings 0, 10, 20, ... toggle while half_period is 10: visible at 1, 11, 21, ... ms.
    assert changes[:4] == [1000, 11000, 21000, 31000]
    toggles, count, level = [], 0, False
    half = 10
    for release in range(0, 2999):  # published by 2999 ms, the last instant of a 3 s run
        if release == 100:
            half = 14
        if release == 250:
            half = 20
        if count == 0:
            level = not level
            toggles.append((release + 1) * 1000)
        count += 1
        if count >= half:
            count = 0
    assert changes == toggles


def _generated(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(out.iterdir()) if p.is_file() and not os.access(p, os.X_OK)}


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_generation_is_deterministic(name, sanitized):
    """The session's build of the example and a second generation into the
    same folder (another hash seed, so set or dict orders that leak would
    show) write byte-identical files."""
    model = next(p for p in EXAMPLES if p.stem == name)
    out = sanitized[name].parent
    first = _generated(out)
    assert "model.c" in first
    # Same flags as the session build: its program is rebuilt as it was.
    env = dict(os.environ, PYTHONHASHSEED="0" if os.environ.get("PYTHONHASHSEED") != "0" else "1")
    proc = cli("build", model, "--board", "host", "-o", out, f"--cflags={SANITIZE}", env=env)
    assert proc.returncode == 0, proc.stderr
    assert _generated(out) == first, "a second generation differs"


@pytest.mark.parametrize("name", ["pneumatic_cylinder", "pt100_sensor"])
def test_vcd_traces_open_in_gtkwave(name, sanitized, tmp_path):
    """GTKWave's own VCD reader (vcd2fst, Debian's gtkwave) converts the
    trace; converted back (fst2vcd) it holds every variable and the same
    number of value changes."""
    import shutil
    import subprocess

    from native_testlib import run

    assert shutil.which("vcd2fst"), "gtkwave is not installed (make setup installs it)"
    vcd = tmp_path / f"{name}.vcd"
    stim = DATA / f"{name}.stimulus.csv"
    run(sanitized[name], vcd, duration="3s", stimulus=stim if stim.exists() else None)
    fst = tmp_path / f"{name}.fst"
    subprocess.run(["vcd2fst", str(vcd), str(fst)], check=True, capture_output=True, timeout=60)
    back = subprocess.run(["fst2vcd", str(fst)], check=True, capture_output=True, text=True, timeout=60).stdout
    ours = vcd.read_text()

    def names(text):
        return sorted(line.split()[4] for line in text.splitlines() if line.startswith("$var"))

    def changes(text):
        body = text.split("$enddefinitions", 1)[1]
        return sum(1 for line in body.splitlines() if line and line[0] in "01bBrR")

    assert names(back) == names(ours) and len(names(ours)) > 5
    assert changes(back) == changes(ours) > 0
