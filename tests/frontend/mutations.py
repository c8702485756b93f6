"""Token- and line-level mutations of a model's text, for the front end's
robustness tests (tests/frontend/test_mutations.py, under hypothesis) and
the mutation campaign (tests/frontend/mutation_campaign.py, seeded): the
same mutations, drawn by either."""

from __future__ import annotations

import random
import re
from typing import Protocol, Sequence, TypeVar

T = TypeVar("T")

# Whitespace, comments, strings, inline-C delimiters, operators, words, numbers.
TOKEN = re.compile(r'\s+|//[^\n]*|/\*.*?\*/|"(?:[^"\\\n]|\\.)*"|\{\{|\}\}|->|\.\.|[<>=!]=|[A-Za-z_]\w*'
                   r'|\d+(?:\.\d+)?|.', re.S)
INSERTS = [
    "{", "}", "(", ")", "[", "]", ",", ":", "=", "->", "..", ".", "<", ">", '"', "{{", "}}", "/*", "*/", "//",
    "@", "-", "+", "*", "/", "%", "==", "\\", "$", "'", "#", "\t", "\n", "\r", "\f", "\u2028", "é",
    "model", "import", "const", "param", "var", "channel", "device", "type", "actor", "dataflow", "chart",
    "task", "step", "initial", "transition", "when", "run", "entry", "exit", "in", "out", "rate", "delay",
    "part", "claims", "driver", "impl", "state", "start", "stop", "period", "offset", "deadline", "wcet",
    "debug", "modbus", "rtu", "tcp", "on", "baud", "parity", "unit", "port", "range", "service", "persist",
    "ro", "rw", "schedule", "sas", "flat", "min-buffer", "std", "true", "false", "not", "and", "or",
    "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "bool", "time", "string", "number",
    "integer", "T", "x", "y", "0", "1", "-1", "255", "65536", "4294967296", "0x", "0b2", "1.5", "1e40", "007",
    "ms", "s", "us", '"PB5"', '"\\q"', "adc", "uart0", "pin",
]


KEYWORDS = {w for w in INSERTS if w.isalpha() and w.islower() and w not in ("x", "y", "adc", "pin")}


def _significant(tokens: list[str]) -> list[int]:
    """Indices of the tokens that are neither whitespace nor comments."""
    return [i for i, t in enumerate(tokens) if t.strip() and not t.startswith(("//", "/*"))] or [0]


class Chooser(Protocol):
    """Where a mutation's choices come from."""

    def integer(self, lo: int, hi: int) -> int: ...

    def pick(self, items: Sequence[T]) -> T: ...


class SeededChooser:
    """Choices from a seeded random.Random."""

    def __init__(self, seed: int):
        self.rng = random.Random(seed)

    def integer(self, lo: int, hi: int) -> int:
        return self.rng.randint(lo, hi)

    def pick(self, items: Sequence[T]) -> T:
        return self.rng.choice(list(items))


class HypothesisChooser:
    """A mutation's choices drawn by hypothesis (shrinkable): ``draw`` of
    a ``@st.composite`` strategy or ``st.data()``."""

    def __init__(self, draw):
        from hypothesis import strategies as st  # the campaign's seeded runs need no hypothesis
        self.draw = draw
        self.st = st

    def integer(self, lo: int, hi: int) -> int:
        return self.draw(self.st.integers(lo, hi))

    def pick(self, items: Sequence[T]) -> T:
        return self.draw(self.st.sampled_from(items))


def mutate(text: str, choose: Chooser) -> str:
    """One to four deletions, duplications, swaps, insertions or
    replacements of tokens or lines of ``text``."""
    tokens = TOKEN.findall(text)
    words = sorted({t for t in tokens if re.fullmatch(r"[A-Za-z_]\w*|\d+(\.\d+)?", t)} - KEYWORDS)
    for _ in range(choose.integer(1, 4)):
        kind = choose.pick(["delete", "duplicate", "swap", "insert", "replace", "replace", "replace",
                            "delete line", "duplicate line", "swap lines"])
        if kind.endswith(("line", "lines")):
            lines = "".join(tokens).split("\n")
            i = choose.integer(0, len(lines) - 1)
            j = choose.integer(0, len(lines) - 1)
            if kind == "delete line":
                del lines[i]
            elif kind == "duplicate line":
                lines.insert(i, lines[j])
            else:
                lines[i], lines[j] = lines[j], lines[i]
            tokens = TOKEN.findall("\n".join(lines)) or [""]
            continue
        significant = _significant(tokens)
        i = significant[choose.integer(0, len(significant) - 1)]
        if kind == "delete":
            del tokens[i]
        elif kind == "duplicate":
            tokens.insert(i, tokens[i])
        elif kind == "swap":
            j = significant[choose.integer(0, len(significant) - 1)]
            tokens[i], tokens[j] = tokens[j], tokens[i]
        elif kind == "replace":  # a name or number by another of the file: mostly semantic errors
            names = [k for k in significant if tokens[k] in words] or significant
            tokens[names[choose.integer(0, len(names) - 1)]] = choose.pick(words or INSERTS)
        else:
            tokens.insert(i, choose.pick(INSERTS) + choose.pick(["", " "]))
        tokens = tokens or [""]
    return "".join(tokens)


