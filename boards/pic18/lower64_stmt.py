"""64-bit integers for a compiler without them: statements, declarations
and functions of a translation unit (lower64.py has the expressions).

- A declaration of a 64-bit type declares an el_w64_t; an automatic one's
  initializer becomes statements, a static one's is computed here.
- A function with 64-bit parameters takes pointers to them (and copies
  them on entry); one returning a 64-bit value writes it through a first
  parameter `el_ret`. Calls are rewritten to match, so every file of a
  program must go through the pass.
- A loop condition that needs statements is evaluated at the top of an
  endless loop (and `continue` in a `for` goes to its increment).
"""

from __future__ import annotations

import copy

from pycparser import c_ast

from .ctypes64 import CType, LowerError, Target, TypeEnv, const_value, where
from .lower64 import W64, ExprLowerer, Low, addr, assign, call, const, ident, rewrite_wide_decl, store, word

_MASK = 0xFFFFFFFFFFFFFFFF


def fold(e: c_ast.Node, env: TypeEnv) -> int:
    """The value of a static initializer, converted as its casts say."""
    if isinstance(e, c_ast.Cast):
        t = env.of_decl(e.to_type)
        v = fold(e.expr, env)
        if t.kind == "int" and t.bits > 1:
            v &= (1 << t.bits) - 1
            if t.signed and v >> (t.bits - 1):
                v -= 1 << t.bits
        return v
    try:
        return const_value(e)
    except LowerError:
        raise LowerError(f"{where(e)}a 64-bit static initializer that is not a constant the lowering can "
                         f"compute") from None


def _w64_init(value: int) -> c_ast.InitList:
    value &= _MASK
    return c_ast.InitList([const(f"0x{value & 0xFFFFFFFF:08X}UL"), const(f"0x{value >> 32:08X}UL")])


class UnitLowerer:
    """Lowers one translation unit in place."""

    def __init__(self, target: Target, wide_funcs: dict[str, CType] | None = None):
        self.env = TypeEnv(target)
        self.wide_funcs: dict[str, CType] = dict(wide_funcs or {})
        self.x = ExprLowerer(self.env, self.wide_funcs)
        self.ret_wide: CType | None = None
        self.loop_labels = 0

    # ---------------------------------------------------------------- top level

    def unit(self, ast: c_ast.FileAST) -> c_ast.FileAST:
        out = []
        for ext in ast.ext:
            if isinstance(ext, c_ast.FuncDef):
                out.append(self.function(ext))
            elif isinstance(ext, c_ast.Decl):
                out.extend(self.global_decl(ext))
            elif isinstance(ext, c_ast.Typedef):
                self.env.typedef(ext)
                rewrite_wide_decl(ext.type, self.env)
                out.append(ext)
            else:
                out.append(ext)
        ast.ext = out
        return ast

    def signature(self, name: str, fd: c_ast.FuncDecl) -> tuple[list, CType]:
        """Rewrite a function declarator with a 64-bit signature: 64-bit
        parameters by pointer, a 64-bit result through el_ret. Returns the
        copies its body starts with, and its type."""
        t = self.env.of_decl(fd)
        wide = t.to.wide or any(p is not None and p.wide for p in t.params)
        prologue = []
        if wide:
            self.wide_funcs[name] = t
            params = []
            for p in (fd.args.params if fd.args else []):
                if isinstance(p, c_ast.Decl) and self.env.of_decl(p.type).wide:
                    arg = f"el_arg_{p.name}" if p.name else None
                    params.append(c_ast.Decl(arg, ["const"], [], [], [], c_ast.PtrDecl([], c_ast.TypeDecl(
                        arg, ["const"], None, c_ast.IdentifierType([W64]))), None, None))
                    if p.name:
                        prologue += [c_ast.Decl(p.name, [], [], [], [], c_ast.TypeDecl(
                            p.name, [], None, c_ast.IdentifierType([W64])), None, None),
                            *store(ident(p.name), c_ast.UnaryOp("*", ident(arg)), self.env.of_decl(p.type))]
                else:
                    if isinstance(p, c_ast.Decl):
                        rewrite_wide_decl(p.type, self.env)
                    params.append(p)
            if t.to.wide:
                params.insert(0, c_ast.Decl("el_ret", [], [], [], [], c_ast.PtrDecl([], c_ast.TypeDecl(
                    "el_ret", [], None, c_ast.IdentifierType([W64]))), None, None))
                fd.type = c_ast.TypeDecl(_declname(fd), [], None, c_ast.IdentifierType(["void"]))
            params = [p for p in params if not _is_void(p)] or [_void_param()]
            fd.args = c_ast.ParamList(params)
        else:
            for p in (fd.args.params if fd.args else []):
                if isinstance(p, c_ast.Decl):
                    rewrite_wide_decl(p.type, self.env)
            rewrite_wide_decl(fd.type, self.env)
        return prologue, t

    def global_decl(self, d: c_ast.Decl) -> list:
        if isinstance(d.type, c_ast.FuncDecl):
            _, t = self.signature(d.name, d.type)
            if d.name:
                self.env.declare(d.name, t)
            return [d]
        t = self.env.of_decl(d.type)
        if d.name:
            self.env.declare(d.name, t)
        if d.init is not None:
            d.init = self.static_init(t, d.init)
        rewrite_wide_decl(d.type, self.env)
        return [d]

    def static_init(self, t: CType, init: c_ast.Node) -> c_ast.Node:
        """A static initializer with its 64-bit parts computed here."""
        if t.wide:
            return _w64_init(fold(init, self.env))
        if isinstance(init, c_ast.InitList) and t.kind == "array" and t.to is not None:
            return c_ast.InitList([self.static_init(t.to, x) for x in init.exprs])
        if isinstance(init, c_ast.InitList) and t.kind == "struct":
            members = list(self.env.members.get(t.tag, {}).values())
            if any(isinstance(x, c_ast.NamedInitializer) for x in init.exprs):
                if self.x.involves_wide(init) or any(m.wide for m in members):
                    raise LowerError(f"{where(init)}designated initializers of 64-bit members are not supported")
                return init
            return c_ast.InitList([self.static_init(m, x) for m, x in zip(members, init.exprs)])
        if not isinstance(init, c_ast.InitList) and self.x.involves_wide(init):
            return c_ast.Constant("int", str(fold(init, self.env)))
        return init

    def function(self, fdef: c_ast.FuncDef) -> c_ast.FuncDef:
        decl = fdef.decl
        params = {p.name: self.env.of_decl(p.type) for p in (decl.type.args.params if decl.type.args else [])
                  if isinstance(p, c_ast.Decl) and p.name}
        prologue, t = self.signature(decl.name, decl.type)
        self.env.declare(decl.name, t)
        self.env.push()
        for name, pt in params.items():  # a 64-bit parameter's name is its copy in the body
            self.env.declare(name, pt)
        self.x.pool, self.x.in_use = {}, {}
        self.ret_wide = t.to if t.to.wide else None
        body = self.compound(fdef.body)
        self.env.pop()
        temps = [c_ast.Decl(name, [], [], [], [], _typedecl(name, list(key)), None, None)
                 for key, names in self.x.pool.items() for name in names]
        fdef.body = c_ast.Compound(temps + prologue + (body.block_items or []))
        return fdef

    # ---------------------------------------------------------------- statements

    def compound(self, node: c_ast.Compound) -> c_ast.Compound:
        self.env.push()
        items = []
        for item in node.block_items or []:
            items.extend(self.statement(item))
        self.env.pop()
        return c_ast.Compound(items)

    def block(self, node: c_ast.Node | None) -> c_ast.Node | None:
        """A statement in a place that takes one statement (a body)."""
        if node is None:
            return None
        out = self.statement(node)
        return out[0] if len(out) == 1 else c_ast.Compound(out)

    def expr(self, e: c_ast.Node) -> Low:
        self.x.statement_starts()
        return self.x.lower(e)

    def statement(self, s: c_ast.Node) -> list:
        if isinstance(s, c_ast.Compound):
            return [self.compound(s)]
        if isinstance(s, c_ast.Decl):
            return self.local_decl(s)
        if isinstance(s, c_ast.Typedef):
            self.env.typedef(s)
            rewrite_wide_decl(s.type, self.env)
            return [s]
        if isinstance(s, c_ast.If):
            low = self.expr(s.cond)
            return low.pre + [c_ast.If(self.x.cond(low), self.block(s.iftrue), self.block(s.iffalse))]
        if isinstance(s, c_ast.Return):
            if s.expr is None:
                return [s]
            low = self.expr(s.expr)
            if self.ret_wide is not None:
                low = self.x.widen(low, self.ret_wide, s)
                return low.pre + store(c_ast.UnaryOp("*", ident("el_ret")), low.expr, low.t) + [c_ast.Return(None)]
            return low.pre + [c_ast.Return(low.expr)]
        if isinstance(s, c_ast.Switch):
            low = self.expr(s.cond)
            if low.t.wide:
                raise LowerError(f"{where(s)}a switch on a 64-bit value is not supported")
            return low.pre + [c_ast.Switch(low.expr, self.block(s.stmt))]
        if isinstance(s, (c_ast.While, c_ast.DoWhile, c_ast.For)):
            return self.loop(s)
        if isinstance(s, c_ast.Label):
            return [c_ast.Label(s.name, self.block(s.stmt))]
        if isinstance(s, c_ast.Case):
            stmts = [x for item in s.stmts for x in self.statement(item)]
            return [c_ast.Case(s.expr, stmts)]
        if isinstance(s, c_ast.Default):
            return [c_ast.Default([x for item in s.stmts for x in self.statement(item)])]
        if isinstance(s, (c_ast.Break, c_ast.Continue, c_ast.Goto, c_ast.EmptyStatement, c_ast.Pragma)):
            return [s]
        low = self.expr(s)  # an expression statement
        rest = [] if low.t.wide or not _does_something(low.expr) else [low.expr]
        return low.pre + rest

    def local_decl(self, d: c_ast.Decl) -> list:
        if isinstance(d.type, c_ast.FuncDecl):
            _, t = self.signature(d.name, d.type)
            self.env.declare(d.name, t)
            return [d]
        t = self.env.of_decl(d.type)
        if d.name:
            self.env.declare(d.name, t)
        wide_array = t.kind == "array" and t.to is not None and t.to.wide
        if d.init is None or (not t.wide and not wide_array and not self.x.involves_wide(d.init)):
            rewrite_wide_decl(d.type, self.env)
            return [d]
        if "static" in (d.storage or []):
            return self.global_decl(d)
        if isinstance(d.init, c_ast.InitList):
            if not wide_array:
                raise LowerError(f"{where(d)}an initializer list with 64-bit parts is not supported")
            init, d.init = d.init, None
            rewrite_wide_decl(d.type, self.env)
            out = [d]
            for i, v in enumerate(init.exprs):
                low = self.x.widen(self.expr(v), t.to, v)
                out += low.pre + store(c_ast.ArrayRef(ident(d.name), const(str(i))), low.expr, t.to)
            return out
        low = self.expr(d.init)
        if t.wide:
            low = self.x.widen(low, t, d)
            d.init = None
            rewrite_wide_decl(d.type, self.env)
            return [d] + low.pre + store(ident(d.name), low.expr, t)
        low = self.x.narrow(low, t, d)
        d.init = low.expr
        rewrite_wide_decl(d.type, self.env)
        return low.pre + [d]

    def loop(self, s: c_ast.Node) -> list:
        cond = s.cond
        is_for = isinstance(s, c_ast.For)
        nxt = s.next if is_for else None
        init_node = s.init if is_for else None
        wide = any(self.x.involves_wide(n) for n in (cond, nxt) if n is not None) or (
            init_node is not None and not isinstance(init_node, c_ast.DeclList) and self.x.involves_wide(init_node))
        self.env.push()
        init: list = []
        if isinstance(init_node, c_ast.DeclList):
            for d in init_node.decls:
                init += self.local_decl(d)
        elif init_node is not None and wide:
            low = self.expr(init_node)
            init = low.pre + ([low.expr] if _does_something(low.expr) else [])
        body = self.block(s.stmt)
        if not wide:
            self.env.pop()
            if isinstance(s, c_ast.While):
                return [c_ast.While(cond, body)]
            if isinstance(s, c_ast.DoWhile):
                return [c_ast.DoWhile(cond, body)]
            if isinstance(init_node, c_ast.DeclList):
                return [c_ast.Compound(init + [c_ast.For(None, cond, nxt, body)])]
            return [c_ast.For(init_node, cond, nxt, body)]
        # for (;;) { the condition's statements; if (!cond) break; body; next: step }
        label = f"el_w64_next{self.loop_labels}"
        self.loop_labels += 1
        test = []
        if cond is not None:
            low = self.expr(cond)
            test = low.pre + [c_ast.If(c_ast.UnaryOp("!", self.x.cond(low)), c_ast.Break(), None)]
        step = []
        if nxt is not None:
            low = self.expr(nxt)
            step = low.pre + ([low.expr] if _does_something(low.expr) else [])
        self.env.pop()
        if isinstance(s, c_ast.DoWhile):  # continue goes to the condition
            items = [_continue_to(body, label), c_ast.Label(label, c_ast.Compound(test))]
        else:
            if step:
                body = _continue_to(body, label)
            items = test + [body] + ([c_ast.Label(label, c_ast.Compound(step))] if step else [])
        return [c_ast.Compound(init + [c_ast.For(None, None, None, c_ast.Compound(items))])]


# ---------------------------------------------------------------- helpers


def _typedecl(name: str, key: list[str]) -> c_ast.Node:
    pointer = key and key[-1] == "*"
    base = c_ast.TypeDecl(name, [], None, c_ast.IdentifierType(key[:-1] if pointer else key))
    return c_ast.PtrDecl([], base) if pointer else base


def _declname(fd: c_ast.FuncDecl) -> str | None:
    node = fd.type
    while not isinstance(node, c_ast.TypeDecl):
        node = node.type
    return node.declname


def _is_void(p: c_ast.Node) -> bool:
    return isinstance(p, c_ast.Typename) and isinstance(p.type, c_ast.TypeDecl) and \
        isinstance(p.type.type, c_ast.IdentifierType) and p.type.type.names == ["void"]


def _void_param() -> c_ast.Typename:
    return c_ast.Typename(None, [], None, c_ast.TypeDecl(None, [], None, c_ast.IdentifierType(["void"])))


def _does_something(e: c_ast.Node) -> bool:
    return not isinstance(e, (c_ast.ID, c_ast.Constant))


def _continue_to(node: c_ast.Node, label: str) -> c_ast.Node:
    """``continue`` of this loop (not of loops inside it) as ``goto label``."""
    if isinstance(node, c_ast.Continue):
        return c_ast.Goto(label)
    if isinstance(node, (c_ast.For, c_ast.While, c_ast.DoWhile)):
        return node
    node = copy.copy(node)
    for name, child in node.children():
        base = name.split("[")[0]
        if "[" in name:
            items = list(getattr(node, base))
            items[int(name.split("[")[1].rstrip("]"))] = _continue_to(child, label)
            setattr(node, base, items)
        else:
            setattr(node, base, _continue_to(child, label))
    return node


def lower_unit(ast: c_ast.FileAST, target: Target, wide_funcs: dict[str, CType] | None = None) -> dict[str, CType]:
    """Lower one translation unit in place; returns the functions with a
    64-bit signature it declares (for the other units of the program)."""
    lowerer = UnitLowerer(target, wide_funcs)
    lowerer.unit(ast)
    return lowerer.wide_funcs


__all__ = ["lower_unit", "LowerError", "Target", "addr", "call", "word"]
