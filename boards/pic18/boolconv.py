"""Conversions to _Bool written as comparisons with zero.

sdcc 4.2's pic16 port converts a value to _Bool wrongly (its genCast
tests the value with `BTFSC STATUS,Z` where `BTFSS` is meant): `MOVF r,W;
BTFSC STATUS,Z; MOVLW 1` leaves 1 for zero and the value itself for
anything else, so `bool b = x;` is true for every x, and 2 for x == 2.
Every conversion to _Bool goes through it unless sdcc already holds the
value as a truth value: an assignment, an initialisation, a `return`, an
argument of a _Bool parameter, a cast `(bool)e`, a compound assignment
(`b |= x`), and a conditional expression, whose C type is int even when
both its operands are _Bool (std's `y = sel ? a : b` and `y =
EL_COMPARE(...)`). sdcc's comparisons, `!`, `&&` and `||` compute 0 or 1
right (tests/pic18/models/boolconv.elab checks each form in gpsim).

So every such conversion of an operand that is not already a truth value
becomes `(e) != 0`, which has the same value in C and which sdcc
computes right; a compound assignment `b op= e` of a side-effect-free
`b` becomes `b = (b op e) != 0`. The files compiled as they are (the
hardware files) get the same fix in sdcc's assembly
(`fix_bool_casts_in_asm`).
"""

from __future__ import annotations

import re

from pycparser import c_ast

from .ctypes64 import CType, Target, TypeEnv, each_function, pure
from .lower64 import ExprLowerer

_TRUTH_OPS = {"==", "!=", "<", "<=", ">", ">=", "&&", "||"}


def _is_bool(t: CType) -> bool:
    return t.kind == "int" and t.bits == 1


class _Fixer:
    def __init__(self, target: Target):
        self.env = TypeEnv(target)
        self.x = ExprLowerer(self.env, {})
        self.returns: CType | None = None
        self.count = 0

    def truth(self, e: c_ast.Node) -> c_ast.Node:
        """``e`` as a value sdcc converts to _Bool right."""
        if isinstance(e, c_ast.Constant):
            return e  # folded by the compiler, right
        if isinstance(e, c_ast.BinaryOp) and e.op in _TRUTH_OPS or isinstance(e, c_ast.UnaryOp) and e.op == "!":
            return e
        if not isinstance(e, (c_ast.TernaryOp, c_ast.Cast)) and _is_bool(self.x.type_of(e)):
            return e  # a _Bool object or call: no conversion
        self.count += 1
        return c_ast.BinaryOp("!=", e, c_ast.Constant("int", "0"))

    def visit(self, node: c_ast.Node) -> c_ast.Node:
        """The node with its conversions to _Bool rewritten (children first)."""
        if isinstance(node, c_ast.Compound):
            self.env.push()
            node.block_items = [self.visit(item) for item in node.block_items or []]
            self.env.pop()
            return node
        if isinstance(node, c_ast.Decl):
            if isinstance(node.type, c_ast.FuncDecl) or not node.name:
                return node
            t = self.env.of_decl(node.type)
            if node.init is not None and not isinstance(node.init, c_ast.InitList):
                node.init = self.visit(node.init)
                if _is_bool(t):
                    node.init = self.truth(node.init)
            self.env.declare(node.name, t)
            return node
        if isinstance(node, (c_ast.Typedef, c_ast.Typename, c_ast.InitList)):
            return node
        for name, child in node.children():
            base = name.split("[")[0]
            if "[" in name:
                items = list(getattr(node, base))
                items[int(name.split("[")[1].rstrip("]"))] = self.visit(child)
                setattr(node, base, items)
            else:
                setattr(node, base, self.visit(child))
        return self.convert(node)

    def convert(self, node: c_ast.Node) -> c_ast.Node:
        if isinstance(node, c_ast.Assignment) and _is_bool(self.x.type_of(node.lvalue)):
            if node.op == "=":
                node.rvalue = self.truth(node.rvalue)
            elif pure(node.lvalue):
                combined = c_ast.BinaryOp(node.op[:-1], node.lvalue, node.rvalue)
                node = c_ast.Assignment("=", node.lvalue, self.truth(combined))
        elif isinstance(node, c_ast.Return) and node.expr is not None and self.returns is not None \
                and _is_bool(self.returns):
            node.expr = self.truth(node.expr)
        elif isinstance(node, c_ast.Cast) and _is_bool(self.env.of_decl(node.to_type)):
            return self.truth(node.expr)
        elif isinstance(node, c_ast.FuncCall) and node.args is not None:
            f = self.x.type_of(node.name)
            if f.kind == "ptr" and f.to is not None:
                f = f.to
            if f.kind == "func":
                node.args.exprs = [self.truth(a) if k < len(f.params) and f.params[k] is not None
                                   and _is_bool(f.params[k]) else a for k, a in enumerate(node.args.exprs)]
        return node


def fix_bool_conversions(ast: c_ast.FileAST, target: Target) -> int:
    """Rewrite the unit's conversions to _Bool in place; returns how many."""
    f = _Fixer(target)

    def visit(fn: c_ast.FuncDef, t: CType) -> None:
        f.returns = t.to
        f.visit(fn.body)
        f.returns = None
    each_function(ast, f.env, visit)
    return f.count



# sdcc's genCast to _Bool, as it reaches the assembly: the value's bytes
# into W (MOVF, then IORWF for each further byte: Z set when all are zero),
# then the inverted skip.
_BAD_CAST = re.compile(r"(\n\t(?:MOVF|IORWF)\t[^\n]*, W[^\n]*\n)\tBTFSC\tSTATUS, 2\n(\tMOVLW\t0x01\n)")


def fix_bool_casts_in_asm(asm: str) -> tuple[str, int]:
    """sdcc's assembly with any conversion to _Bool that the C pass did not
    reach (a hardware file compiled as it is) made right: `BTFSS` for
    `BTFSC` after the bytes that set Z. Returns the text and how many."""
    fixed, count = _BAD_CAST.subn(lambda m: m.group(1) + "\tBTFSS\tSTATUS, 2\n" + m.group(2), asm)
    return fixed, count
