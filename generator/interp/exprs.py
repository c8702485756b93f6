"""IR expressions (guards, actions, run-time actor arguments) compiled to
Python functions with the arithmetic of the generated C (docs/ir.md,
"Expressions"; runtime_c/el_arith.c).

An expression becomes the source of one Python function of the task's
local copies, the chart's step times and its slots, evaluated with
:func:`eval` once; evaluating it is then one Python call. The node types
decide the operations exactly as ``codegen.c_syntax.ExprWriter`` does for C: integer
``+ - *`` and negation wrap at the operand type, ``/`` and ``%`` follow
``el_div_*``/``el_mod_*``, ``float32`` rounds to single precision after
every operation (NaNs as the host's FPU makes them), ``time`` saturates,
comparisons and ``and``/``or``/``not`` give bools.
"""

from __future__ import annotations

import math
from typing import Callable

from ..core import expr as I
from ..core import types as T
from . import values as V

# The signature of every compiled expression: (locals, step times, slots).
Evaluator = Callable[[list, list, list], object]

_COMPARISONS = ("==", "!=", "<", "<=", ">", ">=")
_FLOAT_OPS = {"+": "add_f32", "-": "sub_f32", "*": "mul_f32", "/": "div_f32"}


def _helpers() -> dict:
    """The functions compiled expressions call, by name."""
    env = {"add_f32": V.add_f32, "sub_f32": V.sub_f32, "mul_f32": V.mul_f32, "div_f32": V.div_f32,
           "time_add": V.time_add, "time_sub": V.time_sub}
    for t in T.INTEGERS:
        env[f"wrap_{t.name}"] = V.wrapper(t)
        env[f"div_{t.name}"] = V.div_integer(t)
        env[f"mod_{t.name}"] = V.mod_integer(t)
    for t in T.SCALARS.values():
        env[f"store_{t.name}"] = V.store(t)
    return env


_HELPERS = _helpers()


class ExprCompiler:
    """Compiles the IR expressions of one task (and, for guards and actions,
    one chart) into Python functions.

    ``step_slots`` gives, for a chart's expressions, the slot of each step
    (``Step.active`` is "the step's slot holds it")."""

    def __init__(self, step_slots: list[int] | None = None):
        self.step_slots = step_slots or []

    def compile(self, expr: I.IExpr, result_type: T.ValueType | None = None) -> Evaluator:
        """A function ``(locals, times, slots) -> value``; with ``result_type``
        the value is converted to it as a C assignment would."""
        text = self.source(expr)
        if result_type is not None and result_type != expr.type:
            text = f"store_{result_type.name}({text})"
        return eval(f"lambda L, TIMES, SLOTS: {text}", dict(_HELPERS))  # noqa: S307 - our own source text

    def source(self, e: I.IExpr) -> str:
        """The Python source text of an expression."""
        if isinstance(e, I.Const):
            value = V.literal(e.type, e.value)
            return f"float({str(value)!r})" if isinstance(value, float) and not math.isfinite(value) else repr(value)
        if isinstance(e, I.Ref):
            if e.kind == "item":
                return f"L[{e.target}][0]"
            if e.kind == "step_time":
                return f"TIMES[{e.target}]"
            return f"(SLOTS[{self.step_slots[e.target]}] == {e.target})"
        if isinstance(e, I.Convert):
            return f"store_{e.type.name}({self.source(e.arg)})"
        if isinstance(e, I.Unary):
            arg = self.source(e.arg)
            if e.op == "not":
                return f"(not {arg})"
            if e.type is T.FLOAT32:
                return f"(-{arg})"
            return f"wrap_{e.type.name}(-{arg})"
        assert isinstance(e, I.Binary)
        a, b = self.source(e.left), self.source(e.right)
        op, t = e.op, e.operand_type
        if op in ("and", "or"):
            return f"({a} {op} {b})"
        if op in _COMPARISONS:
            return f"({a} {op} {b})"
        if t is T.TIME:
            return f"time_{'add' if op == '+' else 'sub'}({a}, {b})"
        if t is T.FLOAT32:
            return f"{_FLOAT_OPS[op]}({a}, {b})"
        if op == "/":
            return f"div_{t.name}({a}, {b})"
        if op == "%":
            return f"mod_{t.name}({a}, {b})"
        return f"wrap_{t.name}({a} {op} {b})"
