"""The value types of the language and the rules that relate them.

These rules are the one place where widening, joins and arithmetic result
types are decided; every later stage (checker, IR, C backend, interpreter)
asks this module instead of deciding again.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction


@dataclass(frozen=True)
class ValueType:
    """A scalar type of the language, with its C spelling and range."""

    name: str
    c_name: str
    bits: int
    signed: bool = False
    is_integer: bool = False
    is_numeric: bool = False

    @property
    def min(self) -> int | None:
        if not self.is_integer:
            return None
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def max(self) -> int | None:
        if not self.is_integer:
            return None
        return (1 << (self.bits - 1)) - 1 if self.signed else (1 << self.bits) - 1

    def __str__(self) -> str:
        return self.name


def _int(name: str, bits: int, signed: bool) -> ValueType:
    return ValueType(name, f"{'' if signed else 'u'}int{bits}_t", bits, signed, True, True)


BOOL = ValueType("bool", "bool", 8)
INT8 = _int("int8", 8, True)
UINT8 = _int("uint8", 8, False)
INT16 = _int("int16", 16, True)
UINT16 = _int("uint16", 16, False)
INT32 = _int("int32", 32, True)
UINT32 = _int("uint32", 32, False)
FLOAT32 = ValueType("float32", "float", 32, True, False, True)
# `time` at run time: milliseconds in a uint32, saturating (docs/language.md).
TIME = ValueType("time", "uint32_t", 32, False, True, False)
# Compile-time only: pin names, units, actor options.
STRING = ValueType("string", "const char *", 0)

# The largest finite float32, (2 - 2**-23) * 2**127.
FLOAT32_MAX = (2 ** 24 - 1) * 2 ** 104


def to_double(value) -> float:
    """``float(value)`` that saturates to +-inf where the exact value (a
    Fraction such as 1e309) is beyond a double, instead of raising."""
    try:
        return float(value)
    except OverflowError:
        return float("inf") if value > 0 else float("-inf")


def show_real(value) -> str:
    """A compile-time real for a message: '%g' of its double, or its power
    of ten where it is beyond a double."""
    double = to_double(value)
    if double not in (float("inf"), float("-inf")):
        return f"{double:g}"
    digits = str(abs(int(value)))
    return f"{'-' if value < 0 else ''}{digits[0]}e+{len(digits) - 1}"


# A `scale` (docs/language.md, "Consts, params, vars") has at most this many decimals.
SCALE_DECIMALS = 9
SCALE_MIN, SCALE_MAX = Fraction(1, 10 ** SCALE_DECIMALS), Fraction(10 ** 6)


def decimal_text(value) -> str | None:
    """A Fraction whose denominator divides 10**SCALE_DECIMALS as plain
    decimal text without trailing zeros ("0.1", "2.5", "10"); None for
    any other value."""
    scaled = value * 10 ** SCALE_DECIMALS
    if scaled.denominator != 1:
        return None
    sign, digits = ("-" if scaled < 0 else ""), str(abs(scaled.numerator)).rjust(SCALE_DECIMALS + 1, "0")
    whole, frac = digits[:-SCALE_DECIMALS], digits[-SCALE_DECIMALS:].rstrip("0")
    return f"{sign}{whole}{'.' + frac if frac else ''}"


def scale_number(text: str | None) -> int | float:
    """An item's scale (decimal text, None for 1) as the JSON number the
    map files carry: exact, having at most 15 significant digits."""
    value = Fraction(text) if text is not None else Fraction(1)
    return int(value) if value.denominator == 1 else float(value)


# The largest `time` (a uint32 count of milliseconds), in microseconds.
TIME_MAX_US = (2 ** 32 - 1) * 1000

SCALARS: dict[str, ValueType] = {t.name: t for t in (BOOL, INT8, UINT8, INT16, UINT16, INT32, UINT32, FLOAT32, TIME)}
ALL_TYPES: dict[str, ValueType] = {**SCALARS, "string": STRING}
INTEGERS = (INT8, UINT8, INT16, UINT16, INT32, UINT32)
# Narrowest first: the order in which a join is searched.
_JOIN_ORDER = (INT8, UINT8, INT16, UINT16, INT32, UINT32, FLOAT32)

BOUNDS = {"number": "any numeric type", "integer": "any integer type"}


def satisfies_bound(t: ValueType, bound: str | None) -> bool:
    """Whether ``t`` may bind a type parameter declared with ``bound``."""
    if bound is None:
        return t is not STRING
    if bound == "number":
        return t.is_numeric
    if bound == "integer":
        return t.is_integer and t is not TIME
    return False


def widens(src: ValueType, dst: ValueType) -> bool:
    """Whether a value of ``src`` converts to ``dst`` without loss.

    Integers widen into integers whose range contains theirs; 8- and 16-bit
    integers widen into float32 (its 24-bit mantissa holds them exactly).
    bool, time and float32 only go to themselves.
    """
    if src == dst:
        return True
    if src.is_integer and src is not TIME and dst.is_integer and dst is not TIME:
        return dst.min <= src.min and src.max <= dst.max
    if dst is FLOAT32:
        return src.is_integer and src is not TIME and src.bits <= 16
    return False


def join(types) -> ValueType | None:
    """The narrowest type every type in ``types`` widens to, or None."""
    types = list(types)
    if not types:
        return None
    first = types[0]
    if all(t == first for t in types):
        return first
    for candidate in _JOIN_ORDER:
        if all(widens(t, candidate) for t in types):
            return candidate
    return None


def arithmetic_result(left: ValueType, right: ValueType) -> ValueType | None:
    """Result type of ``+ - * / %`` on two typed operands, or None if illegal.

    Equal types keep their type. Mixed integers compute in the smallest
    signed type that holds both (up to int32); a mix that needs more than
    int32 (uint32 with a signed type) is an error. float32 with an 8- or
    16-bit integer is float32.
    """
    if left == right and left.is_numeric:
        return left
    if left.is_integer and right.is_integer and TIME not in (left, right):
        for candidate in (INT8, INT16, INT32):
            if widens(left, candidate) and widens(right, candidate):
                return candidate
        if not left.signed and not right.signed:
            return UINT32
        return None
    if FLOAT32 in (left, right):
        other = right if left is FLOAT32 else left
        return FLOAT32 if widens(other, FLOAT32) else None
    return None


def fits(value: int, t: ValueType) -> bool:
    """Whether an integer constant is representable in integer type ``t``."""
    return t.is_integer and t.min <= value <= t.max


def smallest_int_type(value: int) -> ValueType:
    """The narrowest integer type holding ``value`` (signed first), for literals."""
    for t in (INT8, UINT8, INT16, UINT16, INT32, UINT32):
        if fits(value, t):
            return t
    return UINT32


def register_table(t: ValueType, access: str) -> str:
    """The Modbus table of a service item: bools are coils (rw) or discrete
    inputs (ro), other items holding (rw) or input (ro) registers."""
    if t is BOOL:
        return "coil" if access == "rw" else "discrete"
    return "holding" if access == "rw" else "input"


def register_count(t: ValueType) -> int:
    """Addresses an item takes in its table: 1 (a bit or a 16-bit register),
    or 2 for 32-bit values (int32, uint32, float32, time)."""
    return 2 if t.bits == 32 else 1
