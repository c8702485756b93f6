"""Benchmark of remote execution (docs/remote.md): per example, the bytes
of the frames of one release instant (UP + DOWN, on the wire), their time
at 115200 baud and at 1 Mbaud against the earliest deadline, and the round
trip per release instant measured in lock-step between `easylab remote
--fast` and the host board's proxy over a pty (the interpreter's share
included: the slope between two run lengths, so start-up cancels). Prints a table and writes ``<out_dir>/remote.json``.

    python bench/bench_remote.py [out_dir]     (default: bench/results)
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

from easylab.pipeline import lower_file  # noqa: E402
from easylab.remote.budget import link_budget  # noqa: E402
from easylab.remote.device_model import device_model  # noqa: E402
from easylab.remote.proxy import build_proxy  # noqa: E402
from easylab.remote.stimulus import device_columns  # noqa: E402

EXAMPLES = {"blink": "2s", "line_follower": "3s", "pneumatic_cylinder": "3600ms", "pt100_sensor": "3500ms"}
BAUDS = (115200, 1_000_000)


def _device_stimulus(stimulus: Path, program, out: Path) -> Path | None:
    text = device_columns(stimulus.read_text(), program)
    if text is None:
        return None
    out.write_text(text)
    return out


def _round_trip(name: str, program, work: Path, duration: str) -> tuple[int, float]:
    """(release instants, seconds) of a lock-step run of ``duration``."""
    exe = build_proxy(program, "host", work / "proxy").executable
    model_path = ROOT / "examples" / f"{name}.elab"
    stimulus = ROOT / "examples" / f"{name}.stimulus.csv"
    devices = _device_stimulus(stimulus, program, work / "devices.csv")
    link = work / "link"
    proxy = subprocess.Popen([str(exe), "--fast", "--link", f"pty:{link}",
                              *(["--stimulus", str(devices)] if devices else [])],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
    try:
        while not link.exists():
            time.sleep(0.01)
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "easylab", "remote", str(model_path), "--target", str(link), "--fast",
                        "--duration", duration, "--stimulus", str(stimulus)], check=True, stdin=subprocess.DEVNULL,
                       capture_output=True)
        seconds = time.perf_counter() - start
        proxy.wait(timeout=30)
    finally:
        if proxy.poll() is None:
            proxy.kill()
    model = device_model(program)
    per_hyperperiod = sum(1 for i in model.instants if i.release)
    instants = _us(duration) // (model.hyperperiod * model.tick_us) * per_hyperperiod
    return instants, seconds


def _double(duration: str) -> str:
    return f"{2 * _us(duration)}us"


def _us(text: str) -> int:
    from easylab.cli.run_command import parse_duration

    return parse_duration(text)


def main(out_dir: Path, tiny: bool = False) -> None:
    out_dir.mkdir(parents=True, exist_ok=True)
    examples = {"pt100_sensor": "200ms"} if tiny else EXAMPLES
    figures = {}
    print(f"{'example':20} {'bytes/instant':>13} {'115200 baud ms':>14} {'1 Mbaud ms':>10} {'deadline ms':>11} "
          f"{'round trip us':>13}")
    with tempfile.TemporaryDirectory() as tmp:
        for name, duration in examples.items():
            program, _ = lower_file(ROOT / "examples" / f"{name}.elab")
            model = device_model(program)
            worst = {baud: max(link_budget(program, model, baud), key=lambda b: b.wire_us / b.deadline_us)
                     for baud in BAUDS}
            # The slope between a run and one twice as long: start-up (Python, plug-ins, HELLO) cancels.
            n1, t1 = _round_trip(name, program, Path(tmp) / f"{name}-1", duration)
            n2, t2 = _round_trip(name, program, Path(tmp) / f"{name}-2", _double(duration))
            instants, seconds = n2 - n1, t2 - t1
            b = worst[BAUDS[0]]
            figures[name] = {
                "bytes_per_instant": b.up_bytes + b.down_bytes, "up_bytes": b.up_bytes, "down_bytes": b.down_bytes,
                "deadline_ms": b.deadline_us / 1000,
                **{f"wire_ms_{baud}": round(worst[baud].wire_us / 1000, 3) for baud in BAUDS},
                **{f"fits_{baud}": worst[baud].fits for baud in BAUDS},
                "lock_step_instants": instants, "lock_step_round_trip_us": round(seconds / max(instants, 1) * 1e6, 1),
            }
            f = figures[name]
            print(f"{name:20} {f['bytes_per_instant']:>13} {f['wire_ms_115200']:>14} {f['wire_ms_1000000']:>10} "
                  f"{f['deadline_ms']:>11g} {f['lock_step_round_trip_us']:>13}")
    (out_dir / "remote.json").write_text(json.dumps(figures, indent=2) + "\n")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "bench" / "results")
