"""Benchmark of distribution (docs/distribution.md):

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
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))

from netns import namespace_command, namespace_problem  # noqa: E402

from easylab.core import types as T  # noqa: E402
from easylab.ir.dds import HISTORY_DEPTH, DdsExport, idl_text, ros_type_of  # noqa: E402

DDS_LINK_LATENCY_US = 1000  # a DDS link's default `latency` (docs/language.md §11)
PERIOD_US = 1000


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


def main(out_dir: Path, tiny: bool = False) -> None:
    out_dir.mkdir(parents=True, exist_ok=True)
    figures = {}
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
