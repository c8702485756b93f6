"""Benchmark of distribution (docs/distribution.md):

- **The Modbus round on the bus**: the robot example (two ATmega328P
  joints in simavr, the planner on the host) run by `easylab launch
  --fast` at 115200 baud and at 1 Mbaud, each joint's UART bytes logged
  with their simavr cycle (EASYLAB_UART_LOG, boards/avr/sim/avr_sim.c:
  exact). Per slot of the round table (generator/analysis/distribution.py)
  against the measured: the request on the wire, the gap from its end to
  the slave's first response byte (the table's t3.5 + turnaround: the
  slave's end-of-frame silence and its work), the response on the wire;
  the slot with the table's closing t3.5 (the master's wait, not on a
  slave's UART); the sync (its frame and the gap to the slave's echo, in
  lock-step), and the round. Worst over the rounds of the run.
- **DDS latency**: publish-to-receive on loopback, in a private network
  namespace (tools/netns.py), between two processes on Debian's libddsc
  with the exports' QoS and type (bench/dds_latency.c): one sample per
  millisecond, each stamped with CLOCK_MONOTONIC when written and compared
  with the same clock when taken; mean, p50, p99 and max against the
  default `latency` of a DDS link (1 ms).

Prints a table and writes ``<out_dir>/distribution.json``.

    python bench/bench_distribution.py [--tiny] [out_dir]     (default: bench/results)
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))

from netns import namespace_command, namespace_problem  # noqa: E402

from easylab.analysis.distribution import REQUEST_BYTES, RESPONSE_BYTES, SYNC_FRAME_BYTES  # noqa: E402
from easylab.core import types as T  # noqa: E402
from easylab.ir.dds import HISTORY_DEPTH, DdsExport, idl_text, ros_type_of  # noqa: E402
from easylab.pipeline import lower_file  # noqa: E402

DDS_LINK_LATENCY_US = 1000  # a DDS link's default `latency` (docs/language.md §11)
PERIOD_US = 1000
BAUDS = (115200, 1_000_000)


def build_latency_probe(work: Path) -> Path:
    """bench/dds_latency.c with the exports' IDL for one int16 (idlc)."""
    module, struct, member = ros_type_of("bench", "latency", T.INT16, 1)
    export = DdsExport("latency", "var", 0, "lan", 0, "rt/bench/pc/latency", module, struct, member, T.INT16, 1, [])
    (work / "el_dds_types.idl").write_text(idl_text([export]))
    subprocess.run(["idlc", "-o", str(work), str(work / "el_dds_types.idl")], check=True, capture_output=True)
    exe = work / "dds_latency"
    subprocess.run(["gcc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-D_POSIX_C_SOURCE=200809L",
                    f"-DEL_DDS_DEPTH={HISTORY_DEPTH}", f"-I{work}", "-o", str(exe),
                    str(ROOT / "bench" / "dds_latency.c"), str(work / "el_dds_types.c"), "-lddsc"],
                   check=True, capture_output=True, text=True)
    return exe


def dds_latency(work: Path, count: int) -> dict:
    """Latencies (µs) of ``count`` samples, one per PERIOD_US, in a private namespace."""
    problem = namespace_problem()
    if problem:
        raise SystemExit(f"DDS latency: {problem}")
    exe = build_latency_probe(work)
    script = (f"{exe} sub 3 {count} > sub.out & "
              f"until grep -q ready sub.out 2>/dev/null; do sleep 0.05; done; "
              f"{exe} pub 3 {count} {PERIOD_US} && wait $!")
    proc = subprocess.run(namespace_command(["sh", "-c", script]), cwd=work, capture_output=True, text=True,
                          timeout=120 + count * PERIOD_US / 1e6)
    lines = (work / "sub.out").read_text().split()
    if proc.returncode != 0 or lines[:1] != ["ready"]:
        raise SystemExit(f"DDS latency: the probe failed:\n{proc.stdout}{proc.stderr}")
    us = sorted(int(v) / 1000 for v in lines[1:])
    return {"samples": len(us), "lost": count - len(us), "period_us": PERIOD_US, "mean_us": round(statistics.fmean(us), 1),
            "p50_us": round(us[len(us) // 2], 1), "p99_us": round(us[min(len(us) - 1, len(us) * 99 // 100)], 1),
            "max_us": round(us[-1], 1), "link_latency_us": DDS_LINK_LATENCY_US,
            "within_link_latency_percent": round(100 * sum(v <= DDS_LINK_LATENCY_US for v in us) / len(us), 2)}


# ---------------------------------------------------------------- the Modbus round


def _frames(events: list[tuple[int, int]], response: bool) -> list[tuple[list[int], list[int]]]:
    """Split one direction's (cycle, byte) events into Modbus frames: the
    sync (function 6), function 23's request or response, an exception."""
    frames, i = [], 0
    while i + 2 < len(events):
        function = events[i + 1][1]
        if function == 6:
            n = SYNC_FRAME_BYTES
        elif function == 23:
            n = RESPONSE_BYTES + events[i + 2][1] if response else REQUEST_BYTES + events[i + 10][1]
        elif function & 0x80:
            n = 5
        else:
            raise SystemExit(f"bus log: function {function} is not the round's")
        chunk = events[i:i + n]
        frames.append(([c for c, _ in chunk], [b for _, b in chunk]))
        i += n
    return frames


def measured_exchanges(log: Path, clock_hz: int) -> dict[int, list[dict]]:
    """Per function (6: sync, 23: slot), each exchange a slave's UART saw:
    request, gap and response in µs (simavr cycles)."""
    rows = log.read_text().splitlines()[1:]
    rx = [(int(r.split(",")[0]), int(r.split(",")[3])) for r in rows if ",rx," in r]
    tx = [(int(r.split(",")[0]), int(r.split(",")[3])) for r in rows if ",tx," in r]
    per_byte = int(rows[-1].split(",")[4])
    responses = _frames(tx, True)
    out: dict[int, list[dict]] = {6: [], 23: []}
    for cycles, data in _frames(rx, False):
        # the bytes arrive one character apart from the first (the line is idle before a request)
        end = max(cycles[0] + len(data) * per_byte, cycles[-1] + per_byte)
        answer = next((r for r in responses if r[0][0] >= end), None)
        if answer is None:
            continue
        responses.remove(answer)
        us = 1e6 / clock_hz
        out[data[1]].append({"request_us": len(data) * per_byte * us, "gap_us": (answer[0][0] - end) * us,
                             "response_us": (answer[0][-1] + per_byte - answer[0][0]) * us})
    return out


def modbus_round(work: Path, baud: int, duration: str) -> dict:
    """The robot's round at ``baud``: the table's figures and the measured ones."""
    text = (ROOT / "examples" / "robot" / "robot.elab").read_text().replace("baud 115200", f"baud {baud}")
    model = work / f"robot_{baud}" / "robot.elab"
    model.parent.mkdir(parents=True)
    model.write_text(text)
    program, result = lower_file(model)
    if program is None:
        raise SystemExit(result.report())
    (table,) = program.deployment.rounds.values()
    timing = table.timing
    logs = model.parent / "uart"
    logs.mkdir()
    proc = subprocess.run([sys.executable, "-m", "easylab", "launch", str(model), "--fast", "--duration", duration,
                           "--trace-dir", str(model.parent / "traces"), "--build-dir", str(model.parent / "build")],
                          capture_output=True, text=True, timeout=1800, cwd=model.parent,
                          env={**os.environ, "EASYLAB_UART_LOG": str(logs)})
    if proc.returncode != 0:
        raise SystemExit(f"easylab launch at {baud} baud failed:\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}")
    clock_hz = tomllib.loads((ROOT / "boards" / "avr" / "board.toml").read_text())["clock_hz"]
    silence, turnaround = float(timing.silence_us), timing.turnaround_us
    slots, syncs = [], []
    for st in timing.slots:
        seen = measured_exchanges(logs / f"robot.{st.node}-sim.uart.csv", clock_hz)
        if not seen[23]:
            raise SystemExit(f"{st.node}: no slot on its UART at {baud} baud")
        worst = {k: max(e[k] for e in seen[23]) for k in ("request_us", "gap_us", "response_us")}
        length = max(e["request_us"] + e["gap_us"] + e["response_us"] for e in seen[23]) + silence
        slots.append({"node": st.node, "rounds": len(seen[23]),
                      "mean_gap_us": round(statistics.fmean(e["gap_us"] for e in seen[23]), 1),
                      "table": {"request_us": float(st.request_us), "gap_us": silence + turnaround,
                                "response_us": float(st.response_us), "length_us": float(st.length_us)},
                      "measured": {**{k: round(v, 1) for k, v in worst.items()}, "length_us": round(length, 1)}})
        syncs += [e["request_us"] + e["gap_us"] for e in seen[6]]
    sync = max(syncs) if syncs else None
    total = (sync if sync is not None else float(timing.sync_us)) + sum(s["measured"]["length_us"] for s in slots)
    return {"baud": baud, "character_us": float(timing.character_us), "t35_us": silence, "turnaround_us": turnaround,
            "period_us": timing.period_us, "sync": {"table_us": float(timing.sync_us),
                                                    "measured_us": None if sync is None else round(sync, 1)},
            "slots": slots, "round": {"table_us": float(timing.length_us), "measured_us": round(total, 1)}}


def _print_round(r: dict) -> None:
    print(f"\nModbus round of the robot at {r['baud']} baud (character {r['character_us']:.2f} us, "
          f"t3.5 {r['t35_us']:.0f} us, turnaround {r['turnaround_us']} us; table / measured, worst, us):")
    print(f"{'':8} {'request':>17} {'gap':>17} {'response':>17} {'slot':>19}")
    s = r["sync"]
    print(f"{'sync':8} {'':>17} {'':>17} {'':>17} {s['table_us']:>9.1f}/{s['measured_us']!s:>9}")
    for slot in r["slots"]:
        t, m = slot["table"], slot["measured"]
        print(f"{slot['node']:8} " + " ".join(f"{t[k]:>8.1f}/{m[k]:>8.1f}" for k in
                                              ("request_us", "gap_us", "response_us")) +
              f" {t['length_us']:>9.1f}/{m['length_us']:>9.1f}")
    print(f"{'round':8} {r['round']['table_us']:>9.1f}/{r['round']['measured_us']:>9.1f} of a "
          f"{r['period_us']} us period")


def main(out_dir: Path, tiny: bool = False) -> None:
    out_dir.mkdir(parents=True, exist_ok=True)
    figures = {}
    with tempfile.TemporaryDirectory() as tmp:
        for baud in BAUDS:
            figures[f"modbus_round_{baud}"] = r = modbus_round(Path(tmp), baud, "100ms" if tiny else "1s")
            _print_round(r)
    print()
    with tempfile.TemporaryDirectory() as tmp:
        d = dds_latency(Path(tmp), 200 if tiny else 10_000)
    figures["dds_latency"] = d
    print(f"DDS publish-to-receive on loopback ({d['samples']} samples received, {d['lost']} lost, "
          f"one per {d['period_us']} us):")
    print(f"{'mean us':>8} {'p50 us':>7} {'p99 us':>7} {'max us':>7} {'<= 1 ms':>8}")
    print(f"{d['mean_us']:>8} {d['p50_us']:>7} {d['p99_us']:>7} {d['max_us']:>7} "
          f"{d['within_link_latency_percent']:>7}%")
    (out_dir / "distribution.json").write_text(json.dumps(figures, indent=2) + "\n")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--tiny"]
    main(Path(args[0]) if args else ROOT / "bench" / "results", tiny="--tiny" in sys.argv)
