"""Value types of the random models and the C that user actor types of a
random model compute with.

The C written here is portable and free of undefined behaviour on every
board: arithmetic runs in ``uint32_t`` (it wraps), conversions to a
narrower signed type are the implementation's modulo conversion that every
compiler of the project's boards implements, shifts stay below 32 bits,
division is by non-zero constants other than -1 and in ``int32_t`` or
``uint32_t``, and the code is C89 (the f16 board's 16-bit proxy). Whatever
a board computes differently is then the board's fault, not the actor's.
"""

from __future__ import annotations

import random
from dataclasses import dataclass


@dataclass(frozen=True)
class IntType:
    """A model integer type and its C twin."""

    name: str
    bits: int
    signed: bool

    @property
    def c(self) -> str:
        return f"{'' if self.signed else 'u'}int{self.bits}_t"

    @property
    def lo(self) -> int:
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def hi(self) -> int:
        return (1 << (self.bits - 1)) - 1 if self.signed else (1 << self.bits) - 1

    def literal(self, value: int) -> str:
        """``value`` as a C constant of this type on a 16-bit or 32-bit int."""
        if self.signed:
            if value == self.lo:  # -2147483648 is not a literal: -2147483647 - 1
                return f"(({self.c})({value + 1}L - 1L))"
            return f"(({self.c}){value}L)"
        return f"(({self.c}){value}uL)"


INTS = {t.name: t for t in (IntType("int8", 8, True), IntType("uint8", 8, False), IntType("int16", 16, True),
                            IntType("uint16", 16, False), IntType("int32", 32, True), IntType("uint32", 32, False))}
INT_NAMES = list(INTS)
U32 = INTS["uint32"]
I32 = INTS["int32"]


def widens(a: str, b: str) -> bool:
    """docs/language.md §2: a converts to b without a cast."""
    if a == b:
        return True
    if a == "float32" or b == "float32":
        return b == "float32" and a in INTS and INTS[a].bits <= 16
    if a not in INTS or b not in INTS:
        return False
    ta, tb = INTS[a], INTS[b]
    if ta.signed and not tb.signed:
        return False
    if ta.signed == tb.signed:
        return tb.bits > ta.bits
    return tb.bits > ta.bits  # unsigned into a wider signed


def boundary(rng: random.Random, t: str) -> int | float:
    """A value of ``t``, often one at its boundaries (0, 1, -1, min, max)."""
    if t == "float32":
        return rng.choice([0.0, 1.5, -2.25, 1000.0, -0.5, float(rng.randint(-30000, 30000)) / 8])
    if t == "bool":
        return rng.random() < 0.5
    it = INTS[t]
    picks = [0, it.lo, it.hi, 1, it.hi - 1, it.lo + 1]
    if it.signed:
        picks.append(-1)
    if rng.random() < 0.5:
        return rng.choice(picks)
    return rng.randint(it.lo, it.hi)


def model_literal(t: str, value) -> str:
    """``value`` as a constant of the model language."""
    if t == "bool":
        return "true" if value else "false"
    if t == "float32":
        text = repr(float(value))
        return text if "." in text or "e" in text else text + ".0"
    return str(value)


class ExprWriter:
    """Random C expressions of a given integer type over named operands.

    ``operands`` maps a C expression (an input, a parameter, a state
    variable) to its model type name. Every expression converts its operands
    to ``uint32_t`` or ``int32_t`` first, so C's promotions (16-bit or 32-bit
    int) never decide a result."""

    def __init__(self, rng: random.Random, operands: dict[str, str]) -> None:
        self.rng = rng
        self.operands = operands

    def leaf(self) -> str:
        rng = self.rng
        names = [n for n, t in self.operands.items() if t in INTS]
        if names and rng.random() < 0.8:
            return f"(uint32_t){rng.choice(names)}"
        t = INTS[rng.choice(INT_NAMES)]
        return f"(uint32_t){t.literal(boundary(rng, t.name))}"

    def u32(self, depth: int) -> str:
        """An expression of type uint32_t."""
        rng = self.rng
        if depth <= 0 or rng.random() < 0.25:
            return self.leaf()
        kind = rng.choice(["add", "sub", "mul", "and", "or", "xor", "shl", "shr", "div", "sdiv", "mod", "cond",
                           "narrow", "not"])
        a = self.u32(depth - 1)
        if kind in ("add", "sub", "mul", "and", "or", "xor"):
            op = {"add": "+", "sub": "-", "mul": "*", "and": "&", "or": "|", "xor": "^"}[kind]
            return f"({a} {op} {self.u32(depth - 1)})"
        if kind == "shl":
            return f"({a} << {rng.randint(0, 31)})"
        if kind == "shr":
            return f"({a} >> {rng.randint(0, 31)})"
        if kind == "div":
            # the quotient fits 32 bits: the cast keeps the expression uint32_t
            # where unsigned long has 64 (the host board) as where it has 32
            return f"(uint32_t)({a} / {rng.choice([2, 3, 7, 10, 255, 1000, 65537, 4000000000])}uL)"
        if kind == "mod":
            return f"(uint32_t)({a} % {rng.choice([2, 3, 10, 256, 1000, 70000])}uL)"
        if kind == "sdiv":
            k = rng.choice([2, 3, 7, 100, -2, -3, -10, -1000])
            return f"(uint32_t)((int32_t){a} / {k}L)"
        if kind == "cond":
            return f"({self.condition(depth - 1)} ? {a} : {self.u32(depth - 1)})"
        if kind == "not":
            return f"(~{a})"
        # through a narrower type and back: wrap-around at every width
        t = INTS[rng.choice(INT_NAMES)]
        return f"(uint32_t)({t.c}){a}" if not t.signed else f"(uint32_t)(int32_t)({t.c}){a}"

    def condition(self, depth: int) -> str:
        """A C condition (an int 0 or 1)."""
        rng = self.rng
        op = rng.choice(["<", "<=", ">", ">=", "==", "!="])
        if rng.random() < 0.5:
            return f"((int32_t){self.u32(depth)} {op} (int32_t){self.u32(depth)})"
        return f"({self.u32(depth)} {op} {self.u32(depth)})"

    def of(self, t: str, depth: int) -> str:
        """An expression of model type ``t`` (an integer type or bool)."""
        if t == "bool":
            # a _Bool from a conditional and from a comparison, both
            if self.rng.random() < 0.5:
                return f"({self.condition(depth)} ? true : false)"
            return f"(bool){self.condition(depth)}"
        c = INTS[t].c
        return f"({c}){self.u32(depth)}" if not INTS[t].signed else f"({c})(int32_t){self.u32(depth)}"
