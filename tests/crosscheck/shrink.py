"""Shrinking a finding to a small model (docs/testing.md).

Greedy deletion: whole declarations first (an actor type, a dataflow, a
chart, a task; the runs of a removed dataflow or chart go with it), then
single lines, kept whenever the checker still accepts the model and the
finding remains: the mode still gives another trace than local execution,
or still fails with the same first error. The stimulus loses the columns
of items that are gone.

    python tests/crosscheck/shrink.py MODEL.elab MODE [-o OUT.elab]
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from crosscheck import compare, signature, write_case  # noqa: E402


def units(lines: list[str]) -> list[tuple[int, int]]:
    """(first, end) line ranges of top-level blocks, then of single lines."""
    blocks, depth, start = [], 0, None
    for i, line in enumerate(lines):
        opens, closes = line.count("{"), line.count("}")
        if depth == 0 and opens > closes:
            start = i
        depth += opens - closes
        if depth == 0 and start is not None:
            blocks.append((start, i + 1))
            start = None
    singles = [(i, i + 1) for i, line in enumerate(lines) if line.strip() and not line.startswith(("model ", "import "))]
    return blocks + singles


def without(lines: list[str], first: int, end: int) -> list[str]:
    """The lines less [first, end); a removed dataflow's or chart's runs too."""
    gone = re.match(r"(?:dataflow|chart) (\w+)", lines[first])
    rest = lines[:first] + lines[end:]
    if gone:
        rest = [re.sub(rf" run {gone.group(1)}\b", "", line) for line in rest]
    return rest


def stimulus_for(text: str, stimulus: str) -> str:
    """The stimulus's columns whose item the model still declares."""
    rows = [r.split(",") for r in stimulus.splitlines()]
    keep = [0] + [i for i, c in enumerate(rows[0]) if i and re.search(rf"^(?:param|var|device) {c.split('.')[0]}\b",
                                                                      text, re.M)]
    return "\n".join(",".join(r[i] for i in keep) for r in rows) + "\n"


def shrink(model: Path, mode: str, duration_ms: int = 120, log=lambda m: print(m, flush=True)) -> tuple[str, str]:
    """The smallest model (and stimulus) found that keeps ``model``'s
    finding in ``mode``."""
    from easylab.pipeline import check_file

    text = model.read_text()
    stimulus = model.with_suffix(".stimulus.csv").read_text()
    work = Path(tempfile.mkdtemp(prefix="shrink-"))

    def finding(candidate: str, stim: str) -> str | None:
        case = write_case(work / "try", model.stem, candidate, stim, duration_ms)
        results = compare(case, work / "try", [mode])
        if results["local"][0] != "reference":
            return None
        verdict, detail = results[mode]
        return signature(verdict, detail) if verdict in ("differs", "fail") else None

    wanted = finding(text, stimulus)
    if wanted is None:
        raise SystemExit(f"{model}: no finding in {mode} to shrink")
    changed = True
    while changed:  # passes until one removes nothing
        changed = False
        index = 0
        while True:
            lines = text.splitlines()
            candidates = units(lines)
            if index >= len(candidates):
                break
            first, end = candidates[index]
            candidate = "\n".join(without(lines, first, end)) + "\n"
            stim = stimulus_for(candidate, stimulus)
            if check_file(model, text=candidate).model is not None and finding(candidate, stim) == wanted:
                text, stimulus, changed = candidate, stim, True
                log(f"{len(candidate.splitlines())} lines")
                continue  # the same index now names the next unit
            index += 1
    return text, stimulus


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model", type=Path)
    ap.add_argument("mode")
    ap.add_argument("-o", "--output", type=Path, help="where to write the shrunk model (its stimulus beside it)")
    args = ap.parse_args(argv)
    text, stimulus = shrink(args.model, args.mode)
    out = args.output or args.model.with_name(args.model.stem + ".small.elab")
    out.write_text(text)
    out.with_name(out.name.replace(".elab", "") + ".stimulus.csv").write_text(stimulus)
    print(f"{out}: {len(text.splitlines())} lines")
    return 0


if __name__ == "__main__":
    sys.exit(main())
