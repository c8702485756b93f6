#!/usr/bin/env python3
"""The mutation campaign (docs/testing.md, "Mutated models"): N mutants of
the examples and of tests/frontend/models/all_features.elab (mutations.py,
seeded), each through the checker and every accepted one through a host
build. A finding is

- a traceback anywhere (the checker, the lowering, the generator);
- a checker that accepts a model and reports errors, or the reverse;
- a compiler error for a model the checker accepted, unless the mutation
  changed the C inside the model's `{{ }}` blocks or every error is on a
  line of them (the user's own C, e.g. using a state the mutation deleted).

A board's own refusal (a pin the part lacks) is a clean error, counted.
Models with nodes are checked, not built (their nodes need MCU boards).
Identical generated C is compiled once.

    python tests/frontend/mutation_campaign.py -n 10000 [--seed 1] [--jobs 2] [--no-build] [--out DIR]

Exit status 0 when nothing was found, 1 otherwise; findings are written to
DIR/findings/ with the exception or the compiler's output.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import sys
import traceback
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))

from mutations import SeededChooser, mutate  # noqa: E402

SEEDS = [*sorted((ROOT / "examples").glob("*.elab")), HERE / "models" / "all_features.elab"]
INLINE_C = re.compile(r"\{\{.*?\}\}", re.S)


def _user_c(text: str) -> list[str]:
    return sorted(INLINE_C.findall(text))


GCC_ERROR = re.compile(r"^(?P<file>[^:\n]+\.c):(?P<line>\d+):\d+: error:", re.M)


def errors_in_user_c(compiler_output: str, text: str) -> bool:
    """Whether every error the compiler reports is on a line of the
    model's own C (a `{{ }}` block, copied as written into the generated
    file): e.g. an actor body using a state the mutation deleted."""
    user_lines = {line.strip() for block in INLINE_C.findall(text) for line in block[2:-2].splitlines()} - {""}
    errors = list(GCC_ERROR.finditer(compiler_output))
    if not errors:
        return False
    for error in errors:
        try:
            lines = Path(error["file"]).read_text(encoding="utf-8").splitlines()
        except OSError:
            return False
        number = int(error["line"])
        if not 0 < number <= len(lines) or lines[number - 1].strip() not in user_lines:
            return False
    return True


def one(index: int, seed: int, out: Path, build: bool) -> tuple[str, str]:
    """(verdict, detail) of mutant ``index``."""
    from easylab.build import generate
    from easylab.board.contract import CompileOptions
    from easylab.board.registry import load_board
    from easylab.core.errors import BuildError
    from easylab.ir.lower import lower
    from easylab.pipeline import check_file

    source = SEEDS[index % len(SEEDS)]
    original = source.read_text(encoding="utf-8")
    text = mutate(original, SeededChooser(seed * 1_000_003 + index))
    path = source.with_name(f"mutant_{index}.elab")  # imports resolve beside the example
    stage = "check"
    try:
        result = check_file(path, text=text)
        if (result.model is None) != result.diagnostics.has_errors:
            return "finding", "the checker's verdict and its diagnostics disagree"
        if result.model is None:
            return "refused", ""
        if not build:
            return "accepted", ""
        stage = "lower"
        program = lower(result.model, result.timing)
        if program.deployment is not None:
            return "nodes", ""
        stage = "board"
        board = load_board("host").configure(None, False)
        try:
            checked = board.check(program)
        except BuildError:
            return "board refused", ""
        stage = "generate"
        work = out / "builds" / f"m{index}"
        generated = generate(program, board, work, False, checked)
        digest = hashlib.sha256(b"".join(p.read_bytes() for p in sorted(generated))).hexdigest()[:16]
        marker = out / "builds" / "compiled" / digest
        if marker.exists():
            return "built (same C)", ""
        stage = "compile"
        try:
            board.compile(program, checked, work, generated, CompileOptions(False, (), None, None, False))
        except BuildError as err:
            if _user_c(text) != _user_c(original) or errors_in_user_c(str(err), text):
                return "user C", ""
            return "finding", f"compiler error for an accepted model:\n{err}"
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.write_text(str(index))
        return "built", ""
    except Exception:  # any traceback is a finding
        return "finding", f"traceback in {stage}:\n{traceback.format_exc()}"
    finally:
        if build:
            import shutil
            shutil.rmtree(out / "builds" / f"m{index}", ignore_errors=True)


def _chunk(args: tuple[list[int], int, Path, bool]) -> list[tuple[int, str, str]]:
    indices, seed, out, build = args
    return [(i, *one(i, seed, out, build)) for i in indices]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-n", type=int, default=10000, help="mutants (default 10000)")
    ap.add_argument("--seed", type=int, default=1, help="campaign seed (default 1)")
    ap.add_argument("--jobs", type=int, default=2, help="processes (default 2)")
    ap.add_argument("--no-build", action="store_true", help="check only, build nothing")
    ap.add_argument("--out", type=Path, default=ROOT / "build" / "mutations", help="work folder")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    chunks = [list(range(j, args.n, 50 * args.jobs)) for j in range(50 * args.jobs)]
    tally: Counter[str] = Counter()
    findings = args.out / "findings"
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        for results in pool.map(_chunk, [(c, args.seed, args.out, not args.no_build) for c in chunks if c]):
            for index, verdict, detail in results:
                tally[verdict] += 1
                if verdict == "finding":
                    findings.mkdir(exist_ok=True)
                    source = SEEDS[index % len(SEEDS)]
                    text = mutate(source.read_text(encoding="utf-8"), SeededChooser(args.seed * 1_000_003 + index))
                    (findings / f"m{index}.elab").write_text(text, encoding="utf-8")
                    (findings / f"m{index}.txt").write_text(detail, encoding="utf-8")
                    print(f"mutant {index} ({source.name}): {detail.splitlines()[0] if detail else ''}", flush=True)
    summary = {"mutants": args.n, "seed": args.seed, "tally": dict(sorted(tally.items()))}
    (args.out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    for verdict, count in sorted(tally.items()):
        print(f"{verdict:16s} {count}")
    return 1 if tally["finding"] else 0


if __name__ == "__main__":
    sys.exit(main())
