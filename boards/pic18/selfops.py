"""`e ^ e` and `e - e` written as `(e) * 0`.

sdcc 4.2 folds an exclusive or or a difference of an operand with itself
into a constant of the wrong size when the operand is a widening cast
(`(uint32_t)v ^ (uint32_t)v` of an int8_t v), and its pic16 back end then
crashes comparing it ("FATAL Compiler Internal Error in file 'gen.c' line
number '4861' : AOP_SIZE (left) == AOP_SIZE (right)"): `((uint32_t)v ^
(uint32_t)v) < ((uint32_t)v >> 31)` does not compile. `(e) * 0` has the
same type as `e ^ e` and `e - e` (e's promoted type: the usual
conversions of it with int leave it as it is) and the same value, 0, and
sdcc folds it right. Only an operand that is a cast to an integer type
(never a pointer, whose difference `* 0` would not be) and has no side
effects is rewritten: the two evaluations were of the same value.
"""

from __future__ import annotations

from pycparser import c_ast, c_generator

from .ctypes64 import BottomUpRewriter, pure

_TEXT = c_generator.CGenerator()
_INTEGER_NAMES = {"char", "short", "int", "long", "signed", "unsigned", "_Bool", "int8_t", "int16_t", "int32_t",
                  "uint8_t", "uint16_t", "uint32_t"}


def _integer_cast(e: c_ast.Node) -> bool:
    """A cast to an integer type written by name (not through a pointer)."""
    if not isinstance(e, c_ast.Cast) or not isinstance(e.to_type.type, c_ast.TypeDecl):
        return False
    names = getattr(e.to_type.type.type, "names", None)
    return bool(names) and set(names) <= _INTEGER_NAMES


class _Rewriter(BottomUpRewriter):
    def rewrite(self, node: c_ast.Node) -> c_ast.Node:
        if not isinstance(node, c_ast.BinaryOp) or node.op not in ("^", "-") or not _integer_cast(node.left) \
                or not pure(node.left):
            return node
        if _TEXT.visit(node.left) != _TEXT.visit(node.right):
            return node
        self.count += 1
        return c_ast.BinaryOp("*", node.left, c_ast.Constant("int", "0"))


def rewrite_self_operations(ast: c_ast.FileAST) -> int:
    """Rewrite the unit's `e ^ e` and `e - e` in place; returns how many."""
    return _Rewriter().run(ast)
