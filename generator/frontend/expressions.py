"""Typing and constant evaluation of expressions.

Integer literals are *untyped constants* until they meet a typed operand or
a target: ``cycles + 1`` is a uint32 when ``cycles`` is, and ``300`` fits an
int16 parameter. Constant arithmetic follows C on the resulting type
(division truncates toward zero); an overflowing constant is an error.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Callable

from . import ast
from ..core import expr as I
from ..core import types as T
from ..core.source import Diagnostics, Span


@dataclass(frozen=True)
class Symbol:
    """What a name in an expression stands for."""

    kind: str  # const param var device_data step_time step_active formal channel
    type: T.ValueType | None  # None: the declaration has an error, reported there
    value: object | None = None  # the compile-time value, if there is one
    target: object = None  # the resolved declaration, for later stages
    name: str = ""


@dataclass(frozen=True)
class Value:
    """The type (None after an error) and compile-time value of an expression."""

    type: T.ValueType | None
    const: object | None = None
    untyped: bool = False  # an integer constant that may still adapt to context
    node: I.IExpr | None = None  # the typed IR expression (see easylab.irexpr)

    @property
    def is_const(self) -> bool:
        return self.const is not None


ERROR = Value(None)
Resolver = Callable[[ast.Path], "Symbol | tuple[str, str | None]"]  # a Symbol, or (message, hint)


def _trunc_div(a: int, b: int) -> int:
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


def const_node(t: T.ValueType, value) -> I.Const:
    """The IR constant of a compile-time value (time: microseconds -> ms)."""
    if t is T.TIME:
        ms = Fraction(value) / 1000
        return I.Const(t, int(ms) if ms.denominator == 1 else ms)
    if t is T.FLOAT32:
        return I.Const(t, T.to_double(value))
    return I.Const(t, value)


def _const(t: T.ValueType, value, untyped: bool = False) -> Value:
    return Value(t, value, untyped, const_node(t, value))


def _describe(v: Value) -> str:
    if v.untyped:
        return "an integer constant"
    return f"'{v.type}'"


class ExprTyper:
    """Types expressions of one context, reporting errors to ``diags``.

    ``resolve`` maps a path to a :class:`Symbol` or to an error message;
    ``runtime`` says whether values known only at run time are allowed.
    """

    def __init__(self, diags: Diagnostics, resolve: Resolver, *, runtime: bool = True,
                 symbols_used: list | None = None,
                 conversion_hint: Callable[[T.ValueType, T.ValueType], str] | None = None):
        self.diags = diags
        self.resolve = resolve
        self.runtime = runtime
        # How to convert a value of one type for another where it stands
        # (a Cast actor on an edge, by default).
        self.conversion_hint = conversion_hint or (lambda got, want: f"convert explicitly with a Cast<{got}, {want}> actor")
        self.symbols_used = symbols_used if symbols_used is not None else []

    # ------------------------------------------------------------- entry points

    def check(self, e: ast.Expr) -> Value:
        method = getattr(self, "_" + type(e).__name__)
        return method(e)

    def expect(self, e: ast.Expr, target: T.ValueType, what: str) -> Value:
        """Type ``e`` and check it converts to ``target`` without loss."""
        v = self.check(e)
        if v.type is None:
            return v
        if not self.assignable(v, target, e.span, what):
            return ERROR
        if v.const is not None and target is T.FLOAT32 and abs(v.const) > T.FLOAT32_MAX:
            self.diags.error(e.span, f"{what}: {T.show_real(v.const)} is beyond the range of 'float32'")
            return ERROR
        if v.const is not None and target is T.TIME and not 0 <= v.const <= T.TIME_MAX_US:
            self.diags.error(e.span, f"{what}: a 'time' is from 0 to {T.TIME_MAX_US // 1000} ms")
            return ERROR
        if v.is_const:
            return _const(target, Fraction(v.const) if target is T.FLOAT32 else v.const)
        return Value(target, None, False, I.convert(v.node, target))

    def expect_const(self, e: ast.Expr, target: T.ValueType | None, what: str) -> Value:
        """Like :meth:`expect` (or :meth:`check` when ``target`` is None) but
        the value must be known at compile time."""
        v = self.expect(e, target, what) if target is not None else self.check(e)
        if v.type is not None and not v.is_const:
            self.diags.error(e.span, f"{what} must be a compile-time constant",
                             "use literals and consts here, not params, vars or device data")
            return ERROR
        return v

    def assignable(self, v: Value, target: T.ValueType, span: Span, what: str) -> bool:
        if v.untyped:
            if target.is_integer and target is not T.TIME:
                if T.fits(v.const, target):
                    return True
                self.diags.error(span, f"{what}: {v.const} does not fit '{target}' "
                                       f"({target.min}..{target.max})")
                return False
            if target is T.FLOAT32:
                return True
            if target is T.TIME:
                self.diags.error(span, f"{what} is a 'time': write a duration such as '{v.const} ms'")
                return False
        elif T.widens(v.type, target):
            return True
        elif v.type is T.FLOAT32 and target is T.FLOAT32:
            return True
        hint = None
        if v.type is not None and target.is_numeric and v.type.is_numeric:
            hint = self.conversion_hint(v.type, target)
        self.diags.error(span, f"{what} expects '{target}' but the value is {_describe(v)}", hint)
        return False

    # ------------------------------------------------------------- literals

    def _IntLit(self, e: ast.IntLit) -> Value:
        return _const(T.smallest_int_type(e.value), e.value, untyped=True)

    def _RealLit(self, e: ast.RealLit) -> Value:
        return _const(T.FLOAT32, e.value)

    def _DurationLit(self, e: ast.DurationLit) -> Value:
        if self.runtime and e.microseconds % 1000 != 0:
            self.diags.error(e.span, f"'{e.text}' is not a whole number of milliseconds, "
                                     "which run-time 'time' values count")
            return ERROR
        return _const(T.TIME, e.microseconds)

    def _BoolLit(self, e: ast.BoolLit) -> Value:
        return _const(T.BOOL, e.value)

    def _StringLit(self, e: ast.StringLit) -> Value:
        return _const(T.STRING, e.value)

    def _Path(self, e: ast.Path) -> Value:
        sym = self.resolve(e)
        if isinstance(sym, tuple):  # (message, hint): the name does not resolve here
            self.diags.error(e.span, sym[0], sym[1])
            return ERROR
        self.symbols_used.append((e, sym))
        if sym.type is None:  # its declaration has an error, reported there
            return ERROR
        if sym.value is not None:
            return _const(sym.type, sym.value)
        if not self.runtime:
            self.diags.error(e.span, f"'{e.text}' is a {_KIND_WORDS.get(sym.kind, sym.kind)}, "
                                     "known only at run time; a compile-time constant is needed here")
            return ERROR
        kind = sym.kind if sym.kind in ("step_time", "step_active") else "item"
        return Value(sym.type, None, False, I.Ref(sym.type, kind, sym.target, e.text))

    # ------------------------------------------------------------- operators

    def _Unary(self, e: ast.Unary) -> Value:
        v = self.check(e.operand)
        if v.type is None:
            return v
        if e.op == "not":
            if v.type is not T.BOOL:
                self.diags.error(e.span, f"'not' needs a bool operand, not {_describe(v)}")
                return ERROR
            if v.is_const:
                return _const(T.BOOL, not v.const)
            return Value(T.BOOL, None, False, I.Unary(T.BOOL, "not", v.node))
        if not v.type.is_numeric:
            self.diags.error(e.span, f"unary '-' needs a number, not {_describe(v)}")
            return ERROR
        if v.const is None:
            rtype = v.type if v.type.signed else T.arithmetic_result(v.type, T.INT8)
            if rtype is None:
                self.diags.error(e.span, f"cannot negate a '{v.type}'")
                return ERROR
            return Value(rtype, None, False, I.Unary(rtype, "neg", I.convert(v.node, rtype)))
        if v.untyped:
            return _const(T.smallest_int_type(-v.const), -v.const, untyped=True)
        return self._fold(e.span, v.type, -v.const)

    def _Binary(self, e: ast.Binary) -> Value:
        left, right = self.check(e.left), self.check(e.right)
        if left.type is None or right.type is None:
            return ERROR
        op = e.op
        if op in ("and", "or"):
            for side, v in ((e.left, left), (e.right, right)):
                if v.type is not T.BOOL:
                    self.diags.error(side.span, f"'{op}' needs bool operands, not {_describe(v)}")
                    return ERROR
            if left.is_const and right.is_const:
                return _const(T.BOOL, (left.const and right.const) if op == "and" else (left.const or right.const))
            return Value(T.BOOL, None, False, I.Binary(T.BOOL, op, left.node, right.node, T.BOOL))
        operand_type = self._common(e, left, right)
        if operand_type is None:
            return ERROR
        if op in ("==", "!=", "<", "<=", ">", ">="):
            if operand_type in (T.BOOL, T.STRING) and op not in ("==", "!="):
                self.diags.error(e.span, f"'{op}' does not order '{operand_type}' values")
                return ERROR
            if left.is_const and right.is_const:
                a, b = left.const, right.const
                return _const(T.BOOL, {"==": a == b, "!=": a != b, "<": a < b, "<=": a <= b,
                                       ">": a > b, ">=": a >= b}[op])
            return Value(T.BOOL, None, False, I.Binary(T.BOOL, op, I.convert(left.node, operand_type),
                                                       I.convert(right.node, operand_type), operand_type))
        if operand_type is T.TIME and op not in ("+", "-"):
            self.diags.error(e.span, f"'{op}' is not defined on 'time' values (only + and -)")
            return ERROR
        if not operand_type.is_numeric and operand_type is not T.TIME:
            self.diags.error(e.span, f"'{op}' needs numbers, not '{operand_type}'")
            return ERROR
        if not (left.is_const and right.is_const):
            return Value(operand_type, None, False,
                         I.Binary(operand_type, op, I.convert(left.node, operand_type),
                                  I.convert(right.node, operand_type), operand_type))
        a, b = left.const, right.const
        if op in ("/", "%") and b == 0:
            self.diags.error(e.right.span, "division by zero in a constant expression")
            return ERROR
        if operand_type is T.FLOAT32:
            if op == "%":
                self.diags.error(e.span, "'%' needs integer operands")
                return ERROR
            result = {"+": a + b, "-": a - b, "*": a * b, "/": Fraction(a) / Fraction(b) if b else 0}[op]
        else:
            result = {"+": lambda: a + b, "-": lambda: a - b, "*": lambda: a * b,
                      "/": lambda: _trunc_div(a, b), "%": lambda: a - b * _trunc_div(a, b)}[op]()
        if left.untyped and right.untyped:
            return _const(T.smallest_int_type(result), result, untyped=True)
        return self._fold(e.span, operand_type, result)

    def _common(self, e: ast.Binary, left: Value, right: Value) -> T.ValueType | None:
        """The type both operands of a binary operator are computed in."""
        if left.untyped and right.untyped:
            return left.type if left.type == right.type else T.arithmetic_result(left.type, right.type) or T.INT32
        if left.untyped or right.untyped:
            lit, typed = (left, right) if left.untyped else (right, left)
            lit_span = e.left.span if left.untyped else e.right.span
            if typed.type.is_integer and typed.type is not T.TIME and T.fits(lit.const, typed.type):
                return typed.type
            if typed.type is T.FLOAT32:
                return T.FLOAT32
            if typed.type is T.TIME:
                self.diags.error(lit_span, f"'{e.op}' mixes a 'time' with a plain number: "
                                           f"write a duration such as '{lit.const} ms'")
                return None
            result = T.arithmetic_result(typed.type, lit.type) if typed.type.is_integer else None
            if result is None:
                self.diags.error(e.span, f"'{e.op}' cannot combine {_describe(typed)} with {lit.const}")
            return result
        if left.type == right.type:
            return left.type
        result = T.arithmetic_result(left.type, right.type)
        if result is None:
            self.diags.error(e.span, f"'{e.op}' cannot combine {_describe(left)} with {_describe(right)}",
                             "convert one side with a Cast actor in a dataflow")
        return result

    def _fold(self, span: Span, t: T.ValueType, value) -> Value:
        if t.is_integer and t is not T.TIME and not T.fits(value, t):
            self.diags.error(span, f"constant {value} overflows '{t}' ({t.min}..{t.max})")
            return ERROR
        return _const(t, value)


_KIND_WORDS = {
    "param": "param", "var": "var", "device_data": "device datum", "step_time": "step time",
    "step_active": "step state", "channel": "channel",
}
