"""``make demo``: the PT100 smart sensor, built for the host board and run
in virtual time against a stimulus, shown as a table; then every example
checked, analysed and drawn.
"""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

from .cli import main as easylab

MODEL = Path("examples/pt100_sensor.elab")
STIMULUS = Path("examples/pt100_sensor.stimulus.csv")
COLUMNS = ("sensor.raw", "temperature", "t_min", "t_max", "t_mean", "alarm")


def _tenths(value: str) -> str:
    v = int(value)
    return f"{'-' if v < 0 else ''}{abs(v) // 10}.{abs(v) % 10}"


def pt100_table(trace: Path, every_us: int = 100_000) -> str:
    """The traced values every 100 ms (the trace has a row per change)."""
    rows = list(csv.DictReader(trace.open()))
    lines = ["  time   ADC  temperature    min    max   mean  alarm",
             "  ----  ----  -----------  -----  -----  -----  -----"]
    current: dict[str, str] = {}
    index = 0
    end = int(rows[-1]["time_us"]) if rows else 0
    for t in range(0, end + 1, every_us):
        while index < len(rows) and int(rows[index]["time_us"]) <= t:
            current = rows[index]
            index += 1
        lines.append(f"  {t / 1e6:4.1f}  {current['sensor.raw']:>4}  {_tenths(current['temperature']):>8} C  "
                     f"{_tenths(current['t_min']):>5}  {_tenths(current['t_max']):>5}  "
                     f"{_tenths(current['t_mean']):>5}  {'ON' if current['alarm'] == '1' else 'off':>5}")
    return "\n".join(lines)


def main() -> int:
    """Run the demo from the project's root folder."""
    if not MODEL.is_file():
        print("demo: run it from the project's root folder (examples/ not found)", file=sys.stderr)
        return 1
    out = Path("build/demo")
    out.mkdir(parents=True, exist_ok=True)
    print(f"== {MODEL}: build for the host board")
    exe_dir = out / "pt100_sensor"
    if easylab(["build", str(MODEL), "--board", "host", "-o", str(exe_dir)]) != 0:
        return 1
    trace = out / "pt100_sensor.trace.csv"
    cmd = [str(exe_dir / "pt100_sensor"), "--fast", "--duration", "3100ms", "--stimulus", str(STIMULUS),
           "--trace", str(trace)]
    print("== run in virtual time: " + " ".join(cmd))
    proc = subprocess.run(cmd)
    if proc.returncode != 0:
        return proc.returncode
    print("== the trace, every 100 ms (alarm above 80.0 C, off again below 78.0 C)")
    print(pt100_table(trace))
    print(f"   (full trace: {trace}; VCD for GTKWave with --trace x.vcd)")
    # The single-file examples, and the one in a folder that needs nothing beside it.
    examples = [*sorted(Path("examples").glob("*.elab")), Path("examples/vision_line/vision_line.elab")]
    print("\n== check every example")
    status = easylab(["check", *map(str, examples)])
    for model in examples:
        print(f"\n== {model}: SDF analysis and drawing")
        status |= easylab(["analyze", str(model)])
        status |= easylab(["graph", str(model), "-o", str(out / f"{model.stem}.svg")])
    return status


if __name__ == "__main__":
    sys.exit(main())
