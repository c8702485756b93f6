"""Left shifts by a constant of 8 or more, written as shifts by less than 8.

sdcc 4.2 narrows an operation whose result is cast to a narrower type
(`(uint8_t)(x << 27)`, `(uint8_t)((hi << 8) | lo)`, also through a
temporary used once): the shift then works on the narrow type, by as
many places as the type has bits or more. Its front end turns such a
shift into `(x, 0)` (warning 116) and its pic16 back end either crashes
on it (SIGSEGV) or emits no code for the result, which is then a register
never written: `(uint8_t)((uint32_t)(x << 27) * (c ? s : K))` gave 255
instead of 0. A shift by less than 8 places is narrowed right (the bits
it leaves are C's), so `x << k` for a constant k >= 8 becomes a chain of
shifts of at most 7 places (`x << 8` is `(x << 7) << 1`), which has the
same value in C.
"""

from __future__ import annotations

from pycparser import c_ast

from .ctypes64 import BottomUpRewriter, const_value

STEP = 7  # the widest shift sdcc narrows right


def _count(e: c_ast.Node) -> int | None:
    try:
        return const_value(e)
    except Exception:  # not a constant the pass can compute: left as it is
        return None


class _Splitter(BottomUpRewriter):
    def rewrite(self, node: c_ast.Node) -> c_ast.Node:
        if not isinstance(node, c_ast.BinaryOp) or node.op != "<<":
            return node
        k = _count(node.right)
        if k is None or k <= STEP or k >= 64:
            return node
        self.count += 1
        out = node.left
        while k > 0:
            step = min(k, STEP)
            out = c_ast.BinaryOp("<<", out, c_ast.Constant("int", f"{step}u"))
            k -= step
        return out


def split_shifts(ast: c_ast.FileAST) -> int:
    """Rewrite the unit's left shifts by 8 or more in place; returns how many."""
    return _Splitter().run(ast)
