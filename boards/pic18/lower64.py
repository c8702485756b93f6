"""64-bit integers for a compiler without them: expressions.

sdcc's pic16 port has no `long long`, while the runtime (the dispatcher's
64-bit tick) and std's actors (`T_WIDE`, `PID`) compute in `int64_t`. The
board therefore compiles every portable C file through this C-to-C pass:
each 64-bit integer becomes an `el_w64_t` (two uint32 words, the low one
first, as a little-endian uint64 lies in memory) and each operation on it a
call into `el_pic18_w64.c`, with C's semantics (two's complement, division
truncating toward zero, conversions as gcc does them). Nothing else of the
program changes.

An expression is lowered into statements that compute its wide parts
into temporaries, in an order C allows, and a residual expression; the
operands of `&&`, `||` and `?:` that need statements become `if`s, so
that what C leaves unevaluated stays unevaluated. Statements, declarations
and functions are in lower64_stmt.py.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pycparser import c_ast

from .ctypes64 import FLOAT, I64, U64, CType, LowerError, TypeEnv, where

W64 = "el_w64_t"
W64_TAG = "el_w64"  # struct el_w64: usable before el_pic18_w64.h is read
_ARITH = {"+": "add", "-": "sub", "*": "mul", "&": "and", "|": "or", "^": "xor"}
_DIV = {"/": "div", "%": "mod"}
_SHIFT = {"<<": "shl", ">>": "shr"}
_COMPARE = {"<", ">", "<=", ">=", "==", "!="}
_COMPOUND = {"+=": "+", "-=": "-", "*=": "*", "/=": "/", "%=": "%", "&=": "&", "|=": "|", "^=": "^",
             "<<=": "<<", ">>=": ">>"}


@dataclass
class Low:
    """A lowered expression: statements to run first, then ``expr``, of
    type ``t`` (for a wide type an lvalue of type el_w64_t)."""

    pre: list = field(default_factory=list)
    expr: c_ast.Node | None = None
    t: CType = I64


# ---------------------------------------------------------------- building C


def ident(name: str) -> c_ast.ID:
    return c_ast.ID(name)


def call(name: str, *args: c_ast.Node) -> c_ast.FuncCall:
    return c_ast.FuncCall(ident(name), c_ast.ExprList(list(args)))


def addr(e: c_ast.Node) -> c_ast.Node:
    if isinstance(e, c_ast.UnaryOp) and e.op == "*":
        return e.expr
    return c_ast.UnaryOp("&", e)


def word(e: c_ast.Node, which: str) -> c_ast.StructRef:
    return c_ast.StructRef(e, ".", ident(which))


def const(text: str, kind: str = "int") -> c_ast.Constant:
    return c_ast.Constant(kind, text)


def typename(names: list[str], pointer: bool = False) -> c_ast.Typename:
    decl: c_ast.Node = c_ast.TypeDecl(None, [], None, c_ast.IdentifierType(names))
    if pointer:
        decl = c_ast.PtrDecl([], decl)
    return c_ast.Typename(None, [], None, decl)


def cast(names: list[str], e: c_ast.Node) -> c_ast.Cast:
    return c_ast.Cast(typename(names), e)


def assign(lhs: c_ast.Node, rhs: c_ast.Node, op: str = "=") -> c_ast.Assignment:
    return c_ast.Assignment(op, lhs, rhs)


def store(lhs: c_ast.Node, rhs: c_ast.Node, t: CType) -> list:
    """lhs = rhs; a wide value word by word (sdcc would copy a struct with
    a call to a __memcpy it does not declare)."""
    if not t.wide:
        return [assign(lhs, rhs)]
    if lhs is rhs:
        return []
    return [assign(word(lhs, "lo"), word(rhs, "lo")), assign(word(lhs, "hi"), word(rhs, "hi"))]


def c_names(t: CType) -> list[str]:
    """The type of a temporary: el_w64_t, float or a <stdint.h> type."""
    if t.wide:
        return [W64]
    if t.kind == "float":
        return ["float"]
    if t.kind != "int":
        raise LowerError(f"a temporary of type {t.kind} is not supported")
    if t.bits == 1:
        return ["_Bool"]
    return [f"{'' if t.signed else 'u'}int{t.bits}_t"]


def rewrite_wide_decl(node: c_ast.Node, env: TypeEnv) -> None:
    """Rewrite a declarator whose base type is a 64-bit integer to el_w64_t
    (through pointers, arrays and function results), and the 64-bit
    members of a struct or union it defines."""
    while isinstance(node, (c_ast.PtrDecl, c_ast.ArrayDecl, c_ast.FuncDecl, c_ast.Typename)):
        node = node.type
    if isinstance(node, (c_ast.Struct, c_ast.Union)):
        base = node
    elif isinstance(node, c_ast.TypeDecl):
        base = node.type
    else:
        return
    if isinstance(base, c_ast.IdentifierType) and env.of_decl(base).wide:
        node.type = c_ast.Struct(W64_TAG, None)  # node is the TypeDecl here
    elif isinstance(base, (c_ast.Struct, c_ast.Union)) and base.decls is not None:
        for member in base.decls:
            rewrite_wide_decl(member.type, env)


def has_effects(node: c_ast.Node | None) -> bool:
    """Does evaluating this expression change anything (assignment,
    increment, call)?"""
    if node is None:
        return False
    if isinstance(node, (c_ast.Assignment, c_ast.FuncCall)):
        return True
    if isinstance(node, c_ast.UnaryOp) and node.op in ("++", "--", "p++", "p--"):
        return True
    return any(has_effects(child) for _, child in node.children())


# ---------------------------------------------------------------- expressions


class ExprLowerer:
    """Lowers expressions of one function (temporaries are its own)."""

    def __init__(self, env: TypeEnv, wide_funcs: dict[str, CType]):
        self.env = env
        self.t = env.target
        self.wide_funcs = wide_funcs  # functions whose signature has a wide type
        self.pool: dict[tuple, list[str]] = {}  # type specifiers -> temporaries, declared at the function's start
        self.in_use: dict[tuple, int] = {}  # temporaries of each type taken by the current statement

    # ---- temporaries

    def temp(self, t: CType, pointer: bool = False) -> c_ast.ID:
        """A temporary of type ``t`` (or pointer to it) that no other part of
        the current statement uses."""
        key = (*c_names(t), "*") if pointer else tuple(c_names(t))
        names = self.pool.setdefault(key, [])
        n = self.in_use.get(key, 0)
        if n == len(names):
            names.append(f"el_w64_t{sum(len(v) for v in self.pool.values())}")
        self.in_use[key] = n + 1
        return ident(names[n])

    def statement_starts(self) -> None:
        """Temporaries of the previous statement are free again."""
        self.in_use = {}

    # ---- conversions

    def widen(self, low: Low, to: CType, node: c_ast.Node) -> Low:
        """``low`` converted to the wide type ``to``."""
        if low.t.wide:
            return Low(low.pre, low.expr, to)
        tmp = self.temp(to)
        if low.t.kind == "float":
            fn = "el_w64_from_f32s" if to.signed else "el_w64_from_f32u"
            return Low(low.pre + [call(fn, addr(tmp), low.expr)], tmp, to)
        if low.t.kind != "int":
            raise LowerError(f"{where(node)}a {low.t.kind} converted to a 64-bit integer")
        if low.t.bits >= 32 and not low.t.signed:
            return Low(low.pre + [call("el_w64_from_u32", addr(tmp), cast(["uint32_t"], low.expr))], tmp, to)
        return Low(low.pre + [call("el_w64_from_i32", addr(tmp), cast(["int32_t"], low.expr))], tmp, to)

    def narrow(self, low: Low, to: CType, node: c_ast.Node) -> Low:
        """A wide ``low`` converted to the narrower type ``to``."""
        if not low.t.wide:
            return low
        if to.wide:
            return Low(low.pre, low.expr, to)
        if to.kind == "float":
            fn = "el_w64_to_f32s" if low.t.signed else "el_w64_to_f32u"
            return Low(low.pre, call(fn, addr(low.expr)), to)
        if to.kind != "int":
            raise LowerError(f"{where(node)}a 64-bit integer converted to a {to.kind}")
        if to.bits == 1:
            return Low(low.pre, self.truth(low.expr), to)
        return Low(low.pre, cast(c_names(to), word(low.expr, "lo")), to)

    def convert(self, low: Low, to: CType, node: c_ast.Node) -> Low:
        if to.wide:
            return self.widen(low, to, node)
        return self.narrow(low, to, node)

    @staticmethod
    def truth(e: c_ast.Node) -> c_ast.Node:
        """A wide value's truth: nonzero."""
        return c_ast.BinaryOp("!=", c_ast.BinaryOp("|", word(e, "lo"), word(e, "hi")), const("0UL"))

    # ---- types without lowering

    def type_of(self, e: c_ast.Node) -> CType:
        """The type of an expression that needs no lowering (or of any
        expression, approximately: for deciding whether it is wide)."""
        env, t = self.env, self.t
        if isinstance(e, c_ast.Constant):
            return self.constant_type(e)
        if isinstance(e, c_ast.ID):
            return env.lookup(e.name)
        if isinstance(e, c_ast.Cast):
            return env.of_decl(e.to_type)
        if isinstance(e, c_ast.UnaryOp):
            if e.op in ("sizeof", "_Alignof"):
                return CType("int", t.int_bits, False)
            inner = self.type_of(e.expr)
            if e.op == "&":
                return CType("ptr", to=inner)
            if e.op == "*":
                return inner.to if inner.to is not None else inner
            if e.op == "!":
                return CType("int", t.int_bits, True)
            return t.promote(inner) if e.op in ("-", "+", "~") else inner
        if isinstance(e, c_ast.BinaryOp):
            a, b = self.type_of(e.left), self.type_of(e.right)
            if e.op in _COMPARE or e.op in ("&&", "||"):
                return CType("int", t.int_bits, True)
            if e.op in _SHIFT:
                return t.promote(a)
            if e.op == "-" and a.kind in ("ptr", "array") and b.kind in ("ptr", "array"):
                return CType("int", t.int_bits, True)
            if a.kind in ("ptr", "array"):
                return a if a.kind == "ptr" else CType("ptr", to=a.to)
            if b.kind in ("ptr", "array"):
                return b if b.kind == "ptr" else CType("ptr", to=b.to)
            return t.arithmetic_result(a, b)
        if isinstance(e, c_ast.Assignment):
            return self.type_of(e.lvalue)
        if isinstance(e, c_ast.TernaryOp):
            a, b = self.type_of(e.iftrue), self.type_of(e.iffalse)
            return t.arithmetic_result(a, b) if a.arithmetic and b.arithmetic else a
        if isinstance(e, c_ast.FuncCall):
            f = self.type_of(e.name)
            if f.kind == "ptr" and f.to is not None:
                f = f.to
            return f.to if f.kind == "func" and f.to is not None else CType("int", t.int_bits, True)
        if isinstance(e, c_ast.StructRef):
            base = self.type_of(e.name)
            if e.type == "->":
                base = base.to if base.to is not None else base
            return env.member(base, e.field.name, e)
        if isinstance(e, c_ast.ArrayRef):
            base = self.type_of(e.name)
            if base.kind not in ("ptr", "array"):
                base = self.type_of(e.subscript)
            return base.to if base.to is not None else base
        if isinstance(e, c_ast.ExprList):
            return self.type_of(e.exprs[-1])
        if isinstance(e, c_ast.CompoundLiteral):
            return env.of_decl(e.type)
        return CType("int", t.int_bits, True)

    def constant_type(self, e: c_ast.Constant) -> CType:
        if e.type in ("float", "double") or (e.type not in ("char", "string") and any(
                c in e.value.lower() for c in ".p") and not e.value.lower().startswith("0x")):
            return FLOAT
        if e.type == "string":
            return CType("ptr", to=CType("int", 8, False))
        if e.type == "char":
            return CType("int", self.t.int_bits, True)
        text = e.value.lower()
        suffix = text.rstrip("0123456789abcdefx")
        value = self.int_value(e)
        unsigned = "u" in suffix
        decimal = not text.startswith("0")
        if "ll" in suffix:
            return U64 if unsigned else I64
        for bits in ((self.t.int_bits, self.t.long_bits, 64) if "l" not in suffix else (self.t.long_bits, 64)):
            if (not unsigned) and value < (1 << (bits - 1)):
                return CType("int", bits, True)
            if (unsigned or not decimal) and value < (1 << bits):
                return CType("int", bits, False)
        return U64

    @staticmethod
    def int_value(e: c_ast.Constant) -> int:
        text = e.value.lower().rstrip("ul")
        if text.startswith("0x"):
            return int(text, 16)
        if text.startswith("0b"):
            return int(text, 2)
        if len(text) > 1 and text.startswith("0"):
            return int(text, 8)
        return int(text)

    def involves_wide(self, e: c_ast.Node | None) -> bool:
        """Does any part of this expression have a wide type (or call a
        function with a wide signature)?"""
        if e is None:
            return False
        if isinstance(e, (c_ast.Typename, c_ast.InitList)):
            return False
        if isinstance(e, c_ast.FuncCall) and isinstance(e.name, c_ast.ID) and e.name.name in self.wide_funcs:
            return True
        if isinstance(e, c_ast.Assignment) and self.type_of(e.lvalue).kind == "struct":
            return True  # a struct copy: sdcc's call to __memcpy would not link (_Assignment)
        try:
            if self.type_of(e).wide:
                return True
        except LowerError:
            pass
        if isinstance(e, c_ast.UnaryOp) and e.op in ("sizeof", "_Alignof"):
            return False
        return any(self.involves_wide(child) for _, child in e.children()
                   if not isinstance(child, c_ast.Typename))

    # ---- lowering

    def cond(self, low: Low) -> c_ast.Node:
        """An expression testing ``low``'s truth."""
        return self.truth(low.expr) if low.t.wide else low.expr

    def lower(self, e: c_ast.Node) -> Low:
        """``e`` as statements and a residual expression without wide
        arithmetic (wide values are lvalues of type el_w64_t)."""
        if not self.involves_wide(e):
            return Low([], e, self.type_of(e))
        handler = getattr(self, f"_{type(e).__name__}", None)
        if handler is None:
            raise LowerError(f"{where(e)}64-bit arithmetic in a {type(e).__name__} is not supported")
        return handler(e)

    def lvalue(self, e: c_ast.Node) -> Low:
        """``e`` as an lvalue that may be evaluated more than once."""
        low = self.lower(e)
        if not has_effects(low.expr):
            return low
        ptr = self.temp(low.t, pointer=True)
        return Low(low.pre + [assign(ptr, addr(low.expr))], c_ast.UnaryOp("*", ptr), low.t)

    def _Constant(self, e: c_ast.Constant) -> Low:
        t = self.constant_type(e)
        value = self.int_value(e) & 0xFFFFFFFFFFFFFFFF
        tmp = self.temp(t)
        return Low([assign(word(tmp, "lo"), const(f"0x{value & 0xFFFFFFFF:08X}UL")),
                    assign(word(tmp, "hi"), const(f"0x{value >> 32:08X}UL"))], tmp, t)

    def _ID(self, e: c_ast.ID) -> Low:
        return Low([], e, self.env.lookup(e.name))

    def _Cast(self, e: c_ast.Cast) -> Low:
        to = self.env.of_decl(e.to_type)
        inner = self.lower(e.expr)
        if to.kind == "void":
            return Low(inner.pre, c_ast.Cast(e.to_type, inner.expr if not inner.t.wide else const("0")), to)
        if to.wide or inner.t.wide:
            return self.convert(inner, to, e)
        rewrite_wide_decl(e.to_type, self.env)
        return Low(inner.pre, c_ast.Cast(e.to_type, inner.expr), to)

    def _UnaryOp(self, e: c_ast.UnaryOp) -> Low:
        op = e.op
        if op in ("sizeof", "_Alignof"):
            if isinstance(e.expr, c_ast.Typename):
                rewrite_wide_decl(e.expr, self.env)
                return Low([], e, self.type_of(e))
            if not self.type_of(e.expr).wide:
                return Low([], e, self.type_of(e))
            return Low([], c_ast.UnaryOp(op, typename([W64])), self.type_of(e))
        if op == "&":
            inner = self.lvalue(e.expr)
            return Low(inner.pre, addr(inner.expr), CType("ptr", to=inner.t))
        if op == "*":
            inner = self.lower(e.expr)
            return Low(inner.pre, c_ast.UnaryOp("*", inner.expr), inner.t.to or inner.t)
        if op in ("++", "--", "p++", "p--"):
            return self.increment(e)
        inner = self.lower(e.expr)
        if not inner.t.wide:
            return Low(inner.pre, c_ast.UnaryOp(op, inner.expr), self.type_of(e))
        if op == "+":
            return inner
        if op == "!":
            return Low(inner.pre, c_ast.UnaryOp("!", self.truth(inner.expr)), CType("int", self.t.int_bits, True))
        tmp = self.temp(inner.t)
        fn = {"-": "el_w64_neg", "~": "el_w64_not"}[op]
        return Low(inner.pre + [call(fn, addr(tmp), addr(inner.expr))], tmp, inner.t)

    def increment(self, e: c_ast.UnaryOp) -> Low:
        target = self.lvalue(e.expr)
        if not target.t.wide:
            return Low(target.pre, c_ast.UnaryOp(e.op, target.expr), target.t)
        one = self.temp(target.t)
        pre = target.pre + [call("el_w64_from_i32", addr(one), const("1L"))]
        fn = "el_w64_add" if "+" in e.op else "el_w64_sub"
        if e.op.startswith("p"):  # postfix: the value before
            old = self.temp(target.t)
            return Low(pre + store(old, target.expr, target.t) +
                       [call(fn, addr(target.expr), addr(target.expr), addr(one))], old, target.t)
        return Low(pre + [call(fn, addr(target.expr), addr(target.expr), addr(one))], target.expr, target.t)

    def _BinaryOp(self, e: c_ast.BinaryOp) -> Low:
        if e.op in ("&&", "||"):
            return self.logical(e)
        return self.binary(e.op, self.lower(e.left), self.lower(e.right), e)

    def logical(self, e: c_ast.BinaryOp) -> Low:
        left, right = self.lower(e.left), self.lower(e.right)
        int_t = CType("int", self.t.int_bits, True)
        if not right.pre:
            return Low(left.pre, c_ast.BinaryOp(e.op, self.cond(left), self.cond(right)), int_t)
        tmp = self.temp(int_t)  # the right operand needs statements: run them only when C would evaluate it
        test = tmp if e.op == "&&" else c_ast.UnaryOp("!", tmp)
        then = c_ast.Compound(right.pre + [assign(tmp, c_ast.BinaryOp("!=", self.cond(right), const("0")))])
        return Low(left.pre + [assign(tmp, c_ast.BinaryOp("!=", self.cond(left), const("0"))),
                               c_ast.If(test, then, None)], tmp, int_t)

    def binary(self, op: str, left: Low, right: Low, node: c_ast.Node) -> Low:
        pre = left.pre + right.pre
        int_t = CType("int", self.t.int_bits, True)
        if op in _SHIFT:
            count = self.narrow(right, CType("int", 8, False), node).expr
            if not left.t.wide:
                return Low(pre, c_ast.BinaryOp(op, left.expr, count), self.t.promote(left.t))
            tmp = self.temp(left.t)
            fn = "el_w64_shl" if op == "<<" else ("el_w64_shrs" if left.t.signed else "el_w64_shru")
            return Low(pre + [call(fn, addr(tmp), addr(left.expr), count)], tmp, left.t)
        if left.t.kind in ("ptr", "array") or right.t.kind in ("ptr", "array"):  # pointer arithmetic
            long_t = CType("int", self.t.long_bits, True)
            lhs, rhs = (self.narrow(x, long_t, node) if x.t.wide else x for x in (left, right))
            t = left.t if left.t.kind in ("ptr", "array") else right.t
            return Low(pre, c_ast.BinaryOp(op, lhs.expr, rhs.expr), int_t if op in _COMPARE else t)
        rt = self.t.arithmetic_result(left.t, right.t)
        if not rt.wide:
            lhs, rhs = self.narrow(left, rt, node), self.narrow(right, rt, node)
            t = int_t if op in _COMPARE else rt
            return Low(pre, c_ast.BinaryOp(op, lhs.expr, rhs.expr), t)
        lhs, rhs = self.widen(left, rt, node), self.widen(right, rt, node)
        pre = lhs.pre + rhs.pre
        if op in _COMPARE:
            fn = "el_w64_cmps" if rt.signed else "el_w64_cmpu"
            return Low(pre, c_ast.BinaryOp(op, call(fn, addr(lhs.expr), addr(rhs.expr)), const("0")), int_t)
        if op in _ARITH:
            fn = f"el_w64_{_ARITH[op]}"
        elif op in _DIV:
            fn = f"el_w64_{_DIV[op]}{'s' if rt.signed else 'u'}"
        else:
            raise LowerError(f"{where(node)}operator {op} on 64-bit integers is not supported")
        tmp = self.temp(rt)
        return Low(pre + [call(fn, addr(tmp), addr(lhs.expr), addr(rhs.expr))], tmp, rt)

    def _Assignment(self, e: c_ast.Assignment) -> Low:
        target = self.lvalue(e.lvalue)
        value = self.lower(e.rvalue)
        if target.t.kind == "struct" and not target.t.wide:
            # sdcc 4.2 copies a struct with a call to a __memcpy it does not
            # declare (the program then does not link): memcpy it is.
            source = self.lvalue(e.rvalue) if not has_effects(value.expr) else value
            size = c_ast.UnaryOp("sizeof", target.expr)
            return Low(target.pre + source.pre + [call("memcpy", addr(target.expr), addr(source.expr), size)],
                       target.expr, target.t)
        if e.op == "=":
            if not target.t.wide and not value.t.wide:
                return Low(target.pre + value.pre, assign(target.expr, value.expr), target.t)
            value = self.convert(value, target.t, e)
        else:
            if not target.t.wide and not value.t.wide and not self.t.arithmetic_result(target.t, value.t).wide:
                return Low(target.pre + value.pre, assign(target.expr, value.expr, e.op), target.t)
            value = self.convert(self.binary(_COMPOUND[e.op], Low([], target.expr, target.t), value, e),
                                 target.t, e)
        return Low(target.pre + value.pre + store(target.expr, value.expr, target.t), target.expr, target.t)

    def _TernaryOp(self, e: c_ast.TernaryOp) -> Low:
        test, yes, no = self.lower(e.cond), self.lower(e.iftrue), self.lower(e.iffalse)
        both_arith = yes.t.arithmetic and no.t.arithmetic
        rt = self.t.arithmetic_result(yes.t, no.t) if both_arith else yes.t
        if not rt.wide and not yes.pre and not no.pre:
            return Low(test.pre, c_ast.TernaryOp(self.cond(test), self.convert(yes, rt, e).expr,
                                                 self.convert(no, rt, e).expr), rt)
        if not both_arith:
            raise LowerError(f"{where(e)}a ?: of non-arithmetic values with 64-bit parts is not supported")
        tmp = self.temp(rt)
        branches = []
        for side in (yes, no):
            conv = self.convert(side, rt, e)
            branches.append(c_ast.Compound(conv.pre + store(tmp, conv.expr, rt)))
        return Low(test.pre + [c_ast.If(self.cond(test), branches[0], branches[1])], tmp, rt)

    def _FuncCall(self, e: c_ast.FuncCall) -> Low:
        f = self.type_of(e.name)
        if f.kind == "ptr" and f.to is not None:
            f = f.to
        name = e.name.name if isinstance(e.name, c_ast.ID) else None
        wide_sig = name is not None and name in self.wide_funcs
        if not wide_sig and f.kind == "func" and (f.to.wide or any(p is not None and p.wide for p in f.params)):
            raise LowerError(f"{where(e)}a call through a pointer to a function with 64-bit parameters")
        params = list(f.params) if f.kind == "func" else []
        pre, args = [], []
        for i, arg in enumerate(e.args.exprs if e.args else []):
            low = self.lower(arg)
            p = params[i] if i < len(params) else None
            if p is not None and (p.wide or low.t.wide):
                low = self.convert(low, p, arg)
            elif low.t.wide:
                raise LowerError(f"{where(arg)}a 64-bit argument to a function without a prototype for it")
            pre += low.pre
            args.append(addr(low.expr) if low.t.wide else low.expr)
        ret = f.to if f.kind == "func" and f.to is not None else CType("int", self.t.int_bits, True)
        if wide_sig and ret.wide:
            tmp = self.temp(ret)
            return Low(pre + [c_ast.FuncCall(e.name, c_ast.ExprList([addr(tmp)] + args))], tmp, ret)
        return Low(pre, c_ast.FuncCall(e.name, c_ast.ExprList(args) if args else None), ret)

    def _StructRef(self, e: c_ast.StructRef) -> Low:
        base = self.lower(e.name)
        record = base.t.to if e.type == "->" and base.t.to is not None else base.t
        return Low(base.pre, c_ast.StructRef(base.expr, e.type, e.field), self.env.member(record, e.field.name, e))

    def _ArrayRef(self, e: c_ast.ArrayRef) -> Low:
        base, index = self.lower(e.name), self.lower(e.subscript)
        if base.t.kind not in ("ptr", "array"):  # i[a]
            base, index = index, base
        index = self.narrow(index, CType("int", self.t.long_bits, True), e)
        return Low(base.pre + index.pre, c_ast.ArrayRef(base.expr, index.expr), base.t.to or base.t)

    def _ExprList(self, e: c_ast.ExprList) -> Low:
        pre = []
        for item in e.exprs[:-1]:
            low = self.lower(item)
            pre += low.pre + ([low.expr] if has_effects(low.expr) else [])
        last = self.lower(e.exprs[-1])
        return Low(pre + last.pre, last.expr, last.t)
