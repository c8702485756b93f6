"""Unsigned multiplications by a constant, as shifts and an addition.

sdcc's pic16 port multiplies 16- and 32-bit values through library calls
(__mulint, __mullong: 80 to 300 cycles), even by a constant; generated
schedules index their token buffers with such products (`i * 7u`) and
std's and users' actors multiply by constants. For unsigned operands, where
C's arithmetic is modular, `x * c` equals `(x << a) + (x << b)` or
`(x << a) - x` when c has one or two bits set or is a power of two minus
one; shifts by a constant are inline instructions. Signed products are
left alone (their overflow is undefined, their shifts of negative values
too).
"""

from __future__ import annotations

from pycparser import c_ast

from .ctypes64 import Target, TypeEnv, const_value, each_function, pure
from .lower64 import ExprLowerer


def _plan(c: int) -> tuple[str, int, int] | None:
    """How to multiply by c: ("shift", a, 0), ("add", a, b) or ("sub", a, 0)."""
    if c <= 1:
        return None
    bits = [k for k in range(32) if c >> k & 1]
    if len(bits) == 1:
        return ("shift", bits[0], 0)
    if len(bits) == 2:
        return ("add", bits[1], bits[0])
    if (c + 1) & c == 0:
        return ("sub", (c + 1).bit_length() - 1, 0)
    return None


def _shifted(e: c_ast.Node, k: int) -> c_ast.Node:
    return e if k == 0 else c_ast.BinaryOp("<<", e, c_ast.Constant("int", f"{k}u"))


class _Reducer:
    def __init__(self, target: Target):
        self.env = TypeEnv(target)
        self.x = ExprLowerer(self.env, {})
        self.count = 0

    def reduce(self, node: c_ast.Node) -> c_ast.Node:
        """The expression (or statement) with its eligible products rewritten."""
        if isinstance(node, c_ast.Compound):
            self.env.push()
            node.block_items = [self.reduce(item) for item in node.block_items or []]
            self.env.pop()
            return node
        if isinstance(node, c_ast.Decl):
            if not isinstance(node.type, c_ast.FuncDecl) and node.name:
                self.env.declare(node.name, self.env.of_decl(node.type))
            if node.init is not None and not isinstance(node.init, c_ast.InitList):
                node.init = self.reduce(node.init)
            return node
        if isinstance(node, (c_ast.Typedef, c_ast.Typename)):
            return node
        for name, child in node.children():
            base = name.split("[")[0]
            if "[" in name:
                items = list(getattr(node, base))
                items[int(name.split("[")[1].rstrip("]"))] = self.reduce(child)
                setattr(node, base, items)
            else:
                setattr(node, base, self.reduce(child))
        if isinstance(node, c_ast.BinaryOp) and node.op == "*":
            return self.product(node)
        return node

    def product(self, node: c_ast.BinaryOp) -> c_ast.Node:
        for operand, constant in ((node.left, node.right), (node.right, node.left)):
            if not isinstance(constant, c_ast.Constant) or constant.type not in ("int", "unsigned int") \
                    and not constant.value[:1].isdigit():
                continue
            try:
                c = const_value(constant)
            except Exception:
                continue
            t = self.x.type_of(node)
            plan = _plan(c)
            if plan is None or t.kind != "int" or t.signed or t.bits not in (16, 32) or not pure(operand):
                continue
            kind, a, b = plan
            operand = c_ast.Cast(c_ast.Typename(None, [], None, c_ast.TypeDecl(
                None, [], None, c_ast.IdentifierType([f"uint{t.bits}_t"]))), operand)
            self.count += 1
            if kind == "shift":
                return _shifted(operand, a)
            op = "+" if kind == "add" else "-"
            return c_ast.BinaryOp(op, _shifted(operand, a), _shifted(operand, b))
        return node


def reduce_products(ast: c_ast.FileAST, target: Target) -> int:
    """Rewrite the unit's eligible products in place; returns how many."""
    r = _Reducer(target)
    each_function(ast, r.env, lambda fn, _type: r.reduce(fn.body))
    return r.count
