"""Front-end benchmark: parse and check a generated model of N actor instances.

The model is a set of dataflows, each a chain of std actors fed by device
data and ending in vars, run by tasks; it is what a large application looks
like to the checker. Run: python bench/bench_frontend.py [out_dir] [actors]
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

CHAIN = 50  # actors per dataflow
TASKS = 16  # the dataflows are spread over this many tasks (a model has at most 32)


def generate_model(actors: int) -> str:
    """A valid model text with ``actors`` actor instances."""
    flows = max(1, actors // CHAIN)
    lines = ["model big \"generated benchmark model\"", "import std", "",
             "param gain: int16 = 1000 range 0..2000 service rw"]
    for f in range(flows):
        lines.append(f"device in{f}: AnalogIn(channel = {f})")
        lines.append(f"var out{f}: int16")
    for f in range(flows):
        count = CHAIN if f < flows - 1 else actors - CHAIN * (flows - 1)
        lines.append(f"dataflow Flow{f} {{")
        lines.append("    a0 = Cast<uint16, int16>()")
        for i in range(1, count):
            kind = ("Gain<int16>(k = gain)", "LowPass<int16>(alpha = 300)",
                    "Limit<int16>(min = -1000, max = 1000)")[i % 3]
            lines.append(f"    a{i} = {kind}")
        lines.append(f"    in{f}.value -> a0.x")
        for i in range(1, count):
            lines.append(f"    a{i - 1}.y -> a{i}.x")
        lines.append(f"    a{count - 1}.y -> out{f}")
        lines.append("}")
    for t in range(min(TASKS, flows)):
        runs = " ".join(f"run Flow{f}" for f in range(t, flows, TASKS))
        lines.append(f"task t{t} period 10 ms {{ {runs} }}")
    return "\n".join(lines) + "\n"


def run(actors: int = 5000) -> dict:
    """Time parsing and checking of a generated model; returns the figures."""
    from easylab.pipeline import check_file
    from easylab.frontend.parser import _ast_parser

    text = generate_model(actors)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "big.elab"
        path.write_text(text)
        t0 = time.perf_counter()
        _ast_parser()  # grammar tables: built once per process
        t1 = time.perf_counter()
        result = check_file(path)
        t2 = time.perf_counter()
    if result.model is None:
        raise SystemExit(result.report())
    instances = sum(len(d.instances) for d in result.model.dataflows.values())
    return {"actors": instances, "lines": text.count("\n"), "grammar_s": round(t1 - t0, 3),
            "parse_and_check_s": round(t2 - t1, 3)}


def main(out_dir: Path, tiny: bool = False, actors: int = 5000) -> dict:
    figures = run(100 if tiny else actors)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "frontend.json").write_text(json.dumps(figures, indent=2) + "\n")
    print(f"front end: {figures['actors']} actors, {figures['lines']} lines: parse + check "
          f"{figures['parse_and_check_s']} s (grammar tables {figures['grammar_s']} s)")
    return figures


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "bench/results"),
         actors=int(sys.argv[2]) if len(sys.argv) > 2 else 5000)
