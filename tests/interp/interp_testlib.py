"""Helpers of the local-execution tests: host firmware builds and runs, the
interpreter's command line in-process, and a generator of random typed
expression models (for equivalence with the C arithmetic)."""

from __future__ import annotations

import math
import random
import re
import struct
import subprocess
from pathlib import Path

from easylab.core import types as T
from easylab.build import build
from easylab.cli import main as easylab_main
from easylab.pipeline import lower_file

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
DATA = HERE / "data"
EXAMPLES = ROOT / "examples"


def lower(path: Path):
    """The IR of a model file (the test fails with the report on errors)."""
    program, result = lower_file(path)
    assert program is not None, result.report()
    return program


def build_host(model: Path, out_dir: Path) -> Path:
    """The host-native firmware of a model."""
    return build(lower(model), "host", out_dir).executable


def run_host(exe: Path, trace: Path, duration: str, stimulus: Path | None = None) -> None:
    cmd = [str(exe), "--fast", "--duration", duration, "--trace", str(trace)]
    if stimulus is not None:
        cmd += ["--stimulus", str(stimulus)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr


def run_interp(model: Path, trace: Path, duration: str, stimulus: Path | None = None, *extra: str) -> int:
    """``easylab run MODEL --fast ...`` in this process; returns its status."""
    argv = ["run", str(model), "--fast", "--duration", duration, "--trace", str(trace), *extra]
    if stimulus is not None:
        argv += ["--stimulus", str(stimulus)]
    return easylab_main(argv)


# ====================================================================== random expressions

_INTS = list(T.INTEGERS)
_READS = re.compile(r"\b([ab]\.|[ABC]\.|r\d)")
_INPUT_PORTS = {"int8": "i8", "uint8": "u8", "int16": "i16", "uint16": "u16", "int32": "i32",
                "uint32": "u32", "float32": "f", "time": "t", "bool": "b"}
_FLOAT_LITERALS = ["0.1", "2.5", "1.0e-3", "3.0e38", "100.0", "0.3333", "1.0e-30", "7.0"]
_SPECIAL_FLOATS = [0.0, -0.0, 1.0, -1.5, 3.4028234663852886e38, -3.4028234663852886e38, 1.401298464324817e-45,
                   1.1754943508222875e-38, math.inf, -math.inf, math.nan, 16777217.0, 0.1]


class ExprModel:
    """A random model whose chart's actions compute typed expressions of
    every kind (all value types, mixed widths, wrapping, division by zero,
    float32 rounding and specials, saturating time, step times and
    activity) from two devices of inputs, with a stimulus changing every
    input at every activation."""

    STEPS = ("A", "B", "C")

    def __init__(self, seed: int, count: int = 60):
        self.rnd = random.Random(seed)
        self.targets: list[tuple[str, T.ValueType, str]] = []
        types = [*_INTS, T.FLOAT32, T.BOOL, T.TIME]
        for i in range(count):
            t = types[i % len(types)]
            self.targets.append((f"r{i}", t, self.expr(t, 3, i)))
        self.guards = [self.expr(T.BOOL, 2, count), self.expr(T.BOOL, 2, count)]

    # ------------------------------------------------------------ expressions

    def expr(self, t: T.ValueType, depth: int, index: int) -> str:
        """A random expression of type ``t``; it may read targets before ``index``."""
        rnd = self.rnd
        if depth == 0 or rnd.random() < 0.2:
            return self.leaf(t, index)
        if t is T.BOOL:
            kind = rnd.choice(["cmp", "cmp", "logic", "not", "active"])
            if kind == "cmp":
                u = rnd.choice([*_INTS, T.FLOAT32, T.TIME, T.BOOL])
                op = rnd.choice(["==", "!="] if u is T.BOOL else ["==", "!=", "<", "<=", ">", ">="])
                # Both sides typed: gcc rejects (-Werror=type-limits) e.g. `u8 < 0`,
                # which the language accepts; see the report of the interpreter work.
                return self.binary(op, lambda: self.typed(u, depth - 1, index))
            if kind == "logic":
                return self.binary(rnd.choice(["and", "or"]), lambda: self.expr(t, depth - 1, index))
            if kind == "not":
                return f"(not {self.expr(t, depth - 1, index)})"
            return f"{rnd.choice(self.STEPS)}.active"
        if t is T.TIME:
            if rnd.random() < 0.2:
                return f"{rnd.choice(self.STEPS)}.time"
            return self.binary(rnd.choice("+-"), lambda: self.typed(t, depth - 1, index),
                               lambda: self.expr(t, depth - 1, index))
        if t is T.FLOAT32:
            kind = rnd.choice(["same", "same", "mixed", "neg"])
            if kind == "neg":
                return f"(-{self.typed(t, depth - 1, index)})"
            op = rnd.choice("+-*/")
            if kind == "mixed":
                narrow = rnd.choice([T.INT8, T.UINT8, T.INT16, T.UINT16])
                sides = [lambda: self.typed(narrow, depth - 1, index), lambda: self.typed(t, depth - 1, index)]
                rnd.shuffle(sides)
                return self.binary(op, *sides)
            return self.binary(op, lambda: self.typed(t, depth - 1, index),
                               lambda: self.divisor(t, op, depth - 1, index))
        # integers
        kind = rnd.choice(["same", "same", "mixed", "neg"])
        op = rnd.choice("+-*/%")
        if kind == "neg":
            sources = [u for u in _INTS if (u if u.signed else T.arithmetic_result(u, T.INT8)) == t]
            if sources:
                return f"(-{self.typed(rnd.choice(sources), depth - 1, index)})"
        if kind == "mixed":
            pairs = [(a, b) for a in _INTS for b in _INTS if a != b and T.arithmetic_result(a, b) == t]
            if pairs:
                a, b = rnd.choice(pairs)
                return self.binary(op, lambda: self.typed(a, depth - 1, index), lambda: self.typed(b, depth - 1, index))
        return self.binary(op, lambda: self.typed(t, depth - 1, index), lambda: self.divisor(t, op, depth - 1, index))

    def binary(self, op: str, left, right=None) -> str:
        """``(left op right)`` from two generators, never with both sides the
        same text: gcc folds `x - x` and may then reject a comparison of the
        constant (-Werror=type-limits)."""
        a = left()
        for _ in range(20):
            b = (right or left)()
            if b != a:
                break
        return f"({a} {op} {b})"

    def typed(self, t: T.ValueType, depth: int, index: int) -> str:
        """An expression of type ``t`` that reads something: never a
        constant, whose type could differ (an untyped integer), and which
        gcc could compare at compile time (-Werror=type-limits rejects e.g.
        `t >= 0 ms`, which the language accepts)."""
        if depth == 0 or self.rnd.random() < 0.4:
            return self.reference(t, index)
        text = self.expr(t, depth, index)
        return text if _READS.search(text) else self.reference(t, index)

    def divisor(self, t: T.ValueType, op: str, depth: int, index: int) -> str:
        """A right operand: anything, but never a constant zero divisor."""
        text = self.expr(t, depth, index)
        if op in "/%" and text.strip("()-") in ("0", "0.0"):
            return self.reference(t, index)
        return text

    def reference(self, t: T.ValueType, index: int) -> str:
        earlier = [name for name, tt, _ in self.targets[:index] if tt == t]
        if earlier and self.rnd.random() < 0.25:
            return self.rnd.choice(earlier)
        return f"{self.rnd.choice('ab')}.{_INPUT_PORTS[t.name]}"

    def leaf(self, t: T.ValueType, index: int) -> str:
        if self.rnd.random() < 0.6:
            return self.reference(t, index)
        return self.constant(t)

    def constant(self, t: T.ValueType) -> str:
        rnd = self.rnd
        if t is T.BOOL:
            return rnd.choice(["true", "false"])
        if t is T.TIME:
            return rnd.choice(["0 ms", "5 ms", "1 s", "4294967295 ms", "250 ms"])
        if t is T.FLOAT32:
            text = rnd.choice(_FLOAT_LITERALS)
            return f"(-{text})" if rnd.random() < 0.3 else text
        value = rnd.choice([0, 1, 2, 3, 7, 100, t.max, t.min, rnd.randint(t.min, t.max)] + ([-1] if t.signed else []))
        return f"({value})" if value < 0 else str(value)

    # ------------------------------------------------------------ files

    def model(self) -> str:
        ports = "\n".join(f"    out {port}: {name}" for name, port in _INPUT_PORTS.items())
        lines = ["model exprs \"Random typed expressions\"", "",
                 f"device type Inputs(ch: uint8) {{\n    claims adc[ch]\n{ports}\n    driver \"inputs\"\n}}",
                 "device a: Inputs(ch = 0)", "device b: Inputs(ch = 1)", ""]
        lines += [f"var {name}: {t.name}" for name, t, _ in self.targets]
        entries = "\n".join(f"        entry {name} = {text}" for name, _, text in self.targets)
        lines += ["", "chart Calc {"]
        for step in self.STEPS:
            lines.append(f"    {'initial ' if step == 'A' else ''}step {step} {{\n{entries}\n    }}")
        lines += [f"    transition A -> B when {self.guards[0]}", "    transition A -> C when true",
                  f"    transition B -> A when {self.guards[1]}", "    transition B -> C when true",
                  "    transition C -> A when true", "}", "", "task calc period 10 ms { run Calc }", ""]
        return "\n".join(lines)

    def stimulus(self, rows: int) -> str:
        rnd = self.rnd
        names = [f"{dev}.{port}" for dev in "ab" for port in _INPUT_PORTS.values()]
        out = ["time_us," + ",".join(names)]
        for row in range(rows):
            cells = []
            for name in names:
                port = name.split(".")[1]
                t = next(T.SCALARS[n] for n, p in _INPUT_PORTS.items() if p == port)
                cells.append(self.stimulus_value(t))
            out.append(f"{row * 10000}," + ",".join(cells))
        return "\n".join(out) + "\n"

    def stimulus_value(self, t: T.ValueType) -> str:
        rnd = self.rnd
        if t is T.BOOL:
            return rnd.choice(["0", "1"])
        if t is T.FLOAT32:
            if rnd.random() < 0.5:
                value = rnd.choice(_SPECIAL_FLOATS)
            else:
                value = rnd.uniform(-1, 1) * 10.0 ** rnd.randint(-40, 38)
            value = struct.unpack("<f", struct.pack("<f", value))[0] if math.isfinite(value) else value
            return repr(value)
        if t is T.TIME:
            return str(rnd.choice([0, 1, 5, 1000, 2 ** 32 - 1, 2 ** 32 - 3, rnd.randint(0, 2 ** 32 - 1)]))
        return str(rnd.choice([0, 1, -1 if t.signed else 2, t.min, t.max, t.min + 1, t.max - 1,
                               rnd.randint(t.min, t.max), rnd.randint(-3, 3) if t.signed else rnd.randint(0, 3)]))
