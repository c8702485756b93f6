"""Benchmark of the online mode's polling (`easylab-debug web`,
docs/online.md): refreshes per second and bytes per refresh against the
AVR (ATmega2560) in simavr, its debug UART at 115200 baud on a pty, with 20
and with 100 items in sight, read by the server's own refresh
(host_tools/debug_web/target.py: one snapshot of one instant per refresh)
back to back. Goals: at least 10 refreshes per second with 20 items, 2
with 100. Prints a table and writes ``<out_dir>/debug_web.json``.

    python bench/bench_debug_web.py [out_dir]     (default: bench/results)
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

if __package__ in (None, ""):  # a script from a source checkout
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from source_checkout import make_easylab_importable

    make_easylab_importable()

from easylab.host_tools.debug_map import DebugMap  # noqa: E402
from easylab.host_tools.debug_protocol import DebugClient  # noqa: E402
from easylab.host_tools.debug_web.target import TargetLink  # noqa: E402

BAUD = 115200
MCU = "atmega2560"
SIZES = (20, 100)
GOALS = {20: 10.0, 100: 2.0}  # refreshes per second

MODEL = """model bench_online "Items for the online mode's benchmark"
actor type Count() {{
    out y: int16
    state n: int16
    step {{{{ n = n + 1; y = n; }}}}
}}
{vars}
dataflow D {{
    c = Count()
    c.y -> v0
}}
task main period 10 ms {{ run D }}
debug on uart0 baud {baud}
"""


def bench_model(n: int) -> str:
    """A model of `n` int16 vars, v0 counting at every instant."""
    return MODEL.format(vars="\n".join(f"var v{i}: int16" for i in range(n)), baud=BAUD)


def _simulator(model: Path, out: Path) -> Path:
    proc = subprocess.run([sys.executable, "-m", "easylab", "build", str(model), "--board", "avr", "--mcu", MCU,
                           "--sim", "-o", str(out)], capture_output=True, text=True, timeout=600,
                          stdin=subprocess.DEVNULL, cwd=ROOT)
    if proc.returncode != 0:
        raise RuntimeError(f"the AVR build failed:\n{proc.stdout}{proc.stderr}")
    return next(Path(line.split(": ", 1)[1]) for line in proc.stdout.splitlines() if line.startswith("simulator: "))


def measure(tmp: Path, refreshes: int) -> dict:
    model = tmp / "bench_online.elab"
    model.write_text(bench_model(max(SIZES)))
    sim = _simulator(model, tmp / "avr")
    hw = json.loads((sim.parent / "hw_map.json").read_text())
    uart = next(n for n, u in hw["uarts"].items() if u["use"] == "debug")
    link = tmp / "debug.pty"
    proc = subprocess.Popen([str(sim), f"--uart{uart}", f"pty:{link}"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 30
        while not link.exists():
            if proc.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"simavr did not start: {proc.stderr.read().decode()[-500:]}")
            time.sleep(0.02)
        dmap = DebugMap.load(sim.parent / "debug_map.json")
        client = DebugClient.open(str(link), timeout=2.0, baudrate=BAUD)
        client.hello_again(10.0)
        poller = TargetLink(dmap, str(link))
        figures = {}
        vars_ = [it for it in dmap.items if it.kind == "var"]
        for n in SIZES:
            items = vars_[:n]
            snaps = [poller.read_snapshot(client, items)]  # warm up; then as the server does, knowing the last state
            started = time.perf_counter()
            for _ in range(refreshes):
                snaps.append(poller.read_snapshot(client, items, snaps[-1].halted))
            snaps = snaps[1:]
            seconds = time.perf_counter() - started
            ticks = [s.tick for s in snaps]
            figures[f"items_{n}"] = {
                "items": n, "refreshes": refreshes, "refreshes_per_s": round(refreshes / seconds, 2),
                "bytes_per_refresh": round(sum(s.wire_bytes for s in snaps) / refreshes, 1),
                "round_trips_per_refresh": round(sum(s.round_trips for s in snaps) / refreshes, 2),
                "ms_per_refresh": round(1000 * seconds / refreshes, 2),
                "consistency": sorted({s.consistency for s in snaps}),
                "instants_advanced": ticks[-1] > ticks[0],
                "goal_per_s": GOALS[n], "goal_met": refreshes / seconds >= GOALS[n],
            }
        client.close()
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return figures


def main(out_dir: str | Path = "bench/results", tiny: bool = False) -> dict:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        measured = measure(Path(tmp), refreshes=3 if tiny else 100)
    results = {"mcu": MCU, "baud": BAUD, "simulator": "simavr", "measured": measured}
    (out_dir / "debug_web.json").write_text(json.dumps(results, indent=1) + "\n")
    print(f"Online mode's refresh against the {MCU} in simavr, debug UART at {BAUD} baud")
    print(f"{'items':>6}{'refreshes/s':>13}{'bytes':>8}{'round trips':>13}{'ms':>8}  consistency   goal")
    for m in measured.values():
        print(f"{m['items']:>6}{m['refreshes_per_s']:>13.2f}{m['bytes_per_refresh']:>8.1f}"
              f"{m['round_trips_per_refresh']:>13.2f}{m['ms_per_refresh']:>8.2f}  {','.join(m['consistency']):<13} "
              f">= {m['goal_per_s']:g}/s {'met' if m['goal_met'] else 'NOT met'}")
    return results


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "bench/results")
