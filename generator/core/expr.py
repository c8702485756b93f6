"""Typed expressions of the IR (guards, actions, run-time actor arguments).

The checker's expression typer (:mod:`easylab.expressions`) builds these
nodes while it types, so the types and implicit conversions are decided in
one place. Every node carries its result type; operands of a binary node
already have the operand type (conversions are explicit :class:`Convert`
nodes). Run-time semantics (docs/ir.md): integer arithmetic wraps at the
node's type; ``x / 0`` is 0 and ``x % 0`` is x; ``time`` values are
milliseconds and ``+``/``-`` on them saturate.
"""

from __future__ import annotations

from dataclasses import dataclass

from .types import ValueType


@dataclass(frozen=True)
class IExpr:
    type: ValueType


@dataclass(frozen=True)
class Const(IExpr):
    """A constant: int, bool, float (float32) or int milliseconds (time)."""

    value: object


@dataclass(frozen=True)
class Ref(IExpr):
    """A value read at run time.

    ``kind`` is ``item`` (a param, var or device datum) or ``step_time`` /
    ``step_active`` (of a step of the chart the expression is in). In the
    checked model ``target`` is the DataInfo, DeviceDatum or StepInfo; in
    the IR it is the item id or the step id.
    """

    kind: str
    target: object
    name: str


@dataclass(frozen=True)
class Unary(IExpr):
    op: str  # "neg" | "not"
    arg: IExpr


@dataclass(frozen=True)
class Binary(IExpr):
    """``op`` is one of or and == != < <= > >= + - * / %; for comparisons the
    node's type is bool and ``operand_type`` the type both sides have."""

    op: str
    left: IExpr
    right: IExpr
    operand_type: ValueType


@dataclass(frozen=True)
class Convert(IExpr):
    """A widening conversion of ``arg`` to this node's type."""

    arg: IExpr


def convert(node: IExpr, target: ValueType) -> IExpr:
    """``node`` converted to ``target`` (constants convert in place)."""
    if node.type == target:
        return node
    if isinstance(node, Const):
        value = node.value
        if target.name == "float32":
            value = float(value)
        return Const(target, value)
    return Convert(target, node)


def refs(node: IExpr):
    """Every :class:`Ref` inside an expression, in order."""
    stack = [node]
    while stack:
        n = stack.pop()
        if isinstance(n, Ref):
            yield n
        elif isinstance(n, Unary):
            stack.append(n.arg)
        elif isinstance(n, Convert):
            stack.append(n.arg)
        elif isinstance(n, Binary):
            stack.extend((n.right, n.left))
