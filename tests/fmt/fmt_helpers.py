"""What the formatter's tests share: the repository's models, a model's
IR without its source positions, a text's comments, a whitespace shuffle."""

from __future__ import annotations

import json
import random
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT / "tests" / "frontend"), str(ROOT / "tests" / "crosscheck")]

from mutations import TOKEN  # noqa: E402

from easylab.core.source import ModelError  # noqa: E402
from easylab.frontend.inline_c import blank_inline_c  # noqa: E402
from easylab.ir.program import to_json  # noqa: E402
from easylab.pipeline import lower_file  # noqa: E402

_POSITION = re.compile(r"(\.elab|>):\d+(?::\d+)?")


def repository_models() -> list[Path]:
    """Every .elab file of the repository (the examples, the test models,
    the std library)."""
    out = subprocess.run(["git", "ls-files", "*.elab"], cwd=ROOT, capture_output=True, text=True, check=True)
    return [ROOT / name for name in out.stdout.split()]


def ir_or_errors(path: Path, text: str) -> str:
    """The lowered IR of ``text`` read as the file ``path`` (its imports and
    driver files beside it), as JSON without source positions; for a model
    with errors, its diagnostics' messages."""
    program, result = lower_file(path, text=text)
    if program is None:
        return "\n".join(d.message for d in result.diagnostics.sorted())
    dump = to_json(program)
    dump["program_id"] = 0  # a hash of the dump, positions included
    return _POSITION.sub(r"\1", json.dumps(dump, sort_keys=True))


def comments(text: str) -> list[str]:
    """The comments of a model text (those inside inline C too), in order,
    without trailing blanks."""
    return [t.rstrip() for t in TOKEN.findall(text) if t.startswith(("//", "/*"))]


def shuffle_whitespace(text: str, rng: random.Random) -> str:
    """``text`` with its layout disturbed and its tokens, comments and inline
    C unchanged: every run of blanks outside inline C redrawn (as many line
    breaks, more blank lines where there was one, any indentation, trailing
    blanks). A text whose inline C does not close is returned as it is."""
    try:
        _, blocks = blank_inline_c(text, "<string>")
    except ModelError:
        return text
    inside_c = [(start, start + len(body) + 4) for start, body in blocks.items()]
    out, pos = [], 0
    for tok in TOKEN.findall(text):
        start, pos = pos, pos + len(tok)
        if not tok.isspace() or any(a <= start < b for a, b in inside_c):
            out.append(tok)
            continue
        breaks = tok.count("\n")
        if breaks == 0:
            out.append(rng.choice([" ", "  ", "\t", "     "]))
            continue
        if breaks > 1:
            breaks += rng.randint(0, 2)
        lines = [rng.choice(["", " ", "\t"]) for _ in range(breaks)]
        out.append("\n".join(lines) + "\n" + rng.choice(["", " ", "  ", "\t", "        "]))
    return "".join(out)
