"""Run-time values of the interpreter, exactly as the generated C holds them.

Every value the interpreter keeps (items, task copies, chart times, actor
arguments) is a canonical Python value of its language type:

- ``bool``: a Python bool;
- integers and ``time``: a Python int inside the C type's range;
- ``float32``: a Python float that is exactly representable in IEEE single
  precision (every operation is rounded to single precision, as C does
  with ``float`` operands on a machine without excess precision).

The functions here are the one place where C's conversions are mirrored:
storing into a variable (:func:`store`), wrapping integer arithmetic,
rounding to single precision (:func:`f32`), and the value a C literal
written by the C backend (``codegen.c_syntax.c_literal``) has in the compiled program
(:func:`literal`).
"""

from __future__ import annotations

import ctypes
import math
import platform
import struct
from fractions import Fraction

from ..core import types as T

_FLOAT = struct.Struct("<f")
_FLOAT_BITS = struct.Struct("<I")

# ctypes type of each value type: the layout of buffers and plug-in arguments.
CTYPES = {
    "bool": ctypes.c_bool, "int8": ctypes.c_int8, "uint8": ctypes.c_uint8, "int16": ctypes.c_int16,
    "uint16": ctypes.c_uint16, "int32": ctypes.c_int32, "uint32": ctypes.c_uint32,
    "float32": ctypes.c_float, "time": ctypes.c_uint32,
}

TIME_MAX = 2 ** 32 - 1


def ctype(t: T.ValueType):
    """The ctypes type holding a value of ``t``."""
    return CTYPES[t.name]


def f32(x: float) -> float:
    """``x`` rounded to the nearest float32 (ties to even), as C's
    ``(float)x``; overflow gives an infinity."""
    try:
        return _FLOAT.unpack(_FLOAT.pack(x))[0]
    except OverflowError:
        return math.copysign(math.inf, x)


def f32_bits(x: float) -> int:
    """The IEEE single bit pattern of a float32 value."""
    return _FLOAT_BITS.unpack(_FLOAT.pack(x))[0]


def f32_from_bits(bits: int) -> float:
    return _FLOAT.unpack(_FLOAT_BITS.pack(bits))[0]


def wrapper(t: T.ValueType):
    """A function wrapping an int into the range of integer type ``t``
    (two's complement), as a cast in C does."""
    mask = (1 << t.bits) - 1
    if t.signed:
        half = 1 << (t.bits - 1)
        return lambda v: ((v + half) & mask) - half
    return lambda v: v & mask


def store(t: T.ValueType):
    """A function converting a value to type ``t`` as a C assignment to a
    variable of that type does (the implicit conversion)."""
    if t is T.BOOL:
        return bool
    if t is T.FLOAT32:
        return lambda v: f32(float(v))
    wrap = wrapper(t)

    def to_integer(v):
        if isinstance(v, float):
            v = math.trunc(v) if math.isfinite(v) else 0
        return wrap(int(v))
    return to_integer


def zero(t: T.ValueType):
    """The zero of a type: the value of static C storage at boot."""
    return False if t is T.BOOL else (0.0 if t is T.FLOAT32 else 0)


def literal(t: T.ValueType, value):
    """The run-time value of ``c_literal(t, value)`` once compiled.

    A float32 literal is the decimal text ``repr(float(value))`` with an
    ``f`` suffix, which the C compiler rounds once, from the decimal, to
    single precision; rounding ``float(value)`` would round twice.
    """
    if t is T.FLOAT32:
        return _decimal_to_f32(repr(float(value)))
    return store(t)(value)


def _decimal_to_f32(text: str) -> float:
    """The float32 nearest to the decimal number ``text`` (ties to even)."""
    double = float(text)
    if not math.isfinite(double):
        return double
    exact = Fraction(text)
    # From the largest float32 plus half an ulp on, a literal rounds to infinity.
    if abs(exact) >= T.FLOAT32_MAX + 2 ** 103:
        return math.copysign(math.inf, double)
    near = f32(double)
    if math.isinf(near):  # the double rounded up to that limit, the decimal is below it
        near = math.copysign(float(T.FLOAT32_MAX), double)
    candidates = {near}
    bits = f32_bits(abs(near))
    for step in (-1, 1):
        if 0 <= bits + step < 0x7F800000:
            candidates.add(math.copysign(f32_from_bits(bits + step), double))

    def distance(c: float):
        return abs(Fraction(c) - exact), f32_bits(abs(c)) & 1  # ties: the even mantissa
    return min(candidates, key=distance)


# ---------------------------------------------------------------- C arithmetic


def div_integer(t: T.ValueType):
    """``el_div_*`` of runtime_c/el_arith.c for integer type ``t``: truncates
    toward zero, ``x / 0`` is 0, the most negative value divided by -1 is
    itself."""
    wrap = wrapper(t)

    def divide(a: int, b: int) -> int:
        if b == 0:
            return 0
        q = abs(a) // abs(b)
        return wrap(q if (a < 0) == (b < 0) else -q)
    return divide


def mod_integer(t: T.ValueType):
    """``el_mod_*``: the sign of the dividend, ``x % 0`` is x, ``x % -1`` is 0."""

    def modulo(a: int, b: int) -> int:
        if b == 0:
            return a
        r = abs(a) % abs(b)
        return -r if a < 0 else r
    return modulo


# NaN results as the host's floating-point unit gives them (IEEE 754 leaves
# the sign and payload open): an operand that is a NaN propagates, the
# first one if both are; an invalid operation (inf - inf, 0 * inf, 0 / 0)
# gives the default NaN, which is negative on x86 (SSE) and positive on
# ARM. The generated C keeps the operand order of the model's expression.
_DEFAULT_NAN = f32_from_bits(0xFFC00000 if platform.machine().lower() in ("x86_64", "amd64", "i386", "i686")
                             else 0x7FC00000)


def _nan(a: float, b: float) -> float:
    if a != a:
        return a
    if b != b:
        return b
    return _DEFAULT_NAN


def add_f32(a: float, b: float) -> float:
    r = a + b
    return f32(r) if r == r else _nan(a, b)


def sub_f32(a: float, b: float) -> float:
    r = a - b
    return f32(r) if r == r else _nan(a, b)


def mul_f32(a: float, b: float) -> float:
    r = a * b
    return f32(r) if r == r else _nan(a, b)


def div_f32(a: float, b: float) -> float:
    """``el_div_f32``: ``x / 0.0`` is 0."""
    if b == 0.0:
        return 0.0
    r = a / b
    return f32(r) if r == r else _nan(a, b)


def time_add(a: int, b: int) -> int:
    """``el_time_add``: saturates at the largest time."""
    s = a + b
    return s if s <= TIME_MAX else TIME_MAX


def time_sub(a: int, b: int) -> int:
    """``el_time_sub``: saturates at 0."""
    return a - b if a >= b else 0
