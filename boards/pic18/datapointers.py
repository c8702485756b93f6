"""Pointers that only ever point into RAM, made sdcc `__data` pointers.

A plain C pointer is a generic pointer for sdcc's pic16 port: three bytes,
the third telling RAM, program memory or EEPROM apart, and every access
through it a call of __gptrget/__gptrput. Generated code calls each
actor's step function (a static function) with pointers to its state and
to its tokens, all in RAM, and inline.py turns those parameters into local
pointers: declared `__data`, they are two bytes and accessed through FSR0
directly, several times faster. Nothing else changes; a `__data` pointer
converts to a generic one wherever one is expected.

The rule, per translation unit, with C's scopes:
- a pointer parameter of a static function whose address is never taken
  is `__data` when every call passes the address of a non-const object (or
  of an element or member of one), a non-const array, or a `__data` pointer;
- a local pointer is `__data` when its initializer is such an address and
  the function never assigns it with `=`.
"""

from __future__ import annotations

from pycparser import c_ast

DATA = "__data"
# What a name in scope is, for these rules.
_DATA_PTR, _PTR, _ARRAY, _OBJECT, _ROM = "data pointer", "pointer", "array", "object", "rom"


def _kind(decl: c_ast.Decl, data: bool = False) -> str:
    """What a declared name is; a const object counts as program memory
    (sdcc keeps static ones there; the rule only loses a speed-up)."""
    node = decl.type
    if isinstance(node, c_ast.PtrDecl):
        quals = node.type.quals if isinstance(node.type, c_ast.TypeDecl) else []
        return _DATA_PTR if data or DATA in quals else _PTR
    while isinstance(node, c_ast.ArrayDecl):
        node = node.type
    if "const" in (getattr(node, "quals", None) or []):
        return _ROM
    return _ARRAY if isinstance(decl.type, c_ast.ArrayDecl) else _OBJECT


class _Scopes:
    def __init__(self):
        self.stack: list[dict[str, str]] = [{}]

    def push(self, names: dict[str, str] | None = None) -> None:
        self.stack.append(dict(names or {}))

    def pop(self) -> None:
        self.stack.pop()

    def declare(self, name: str, kind: str) -> None:
        self.stack[-1][name] = kind

    def kind(self, name: str) -> str | None:
        for scope in reversed(self.stack):
            if name in scope:
                return scope[name]
        return None

    def in_ram(self, e: c_ast.Node) -> bool:
        """Does this pointer-valued expression point into RAM for sure?"""
        if isinstance(e, c_ast.Cast):
            return self.in_ram(e.expr)
        if isinstance(e, c_ast.BinaryOp) and e.op in ("+", "-"):
            return self.in_ram(e.left)
        if isinstance(e, c_ast.ID):
            return self.kind(e.name) in (_DATA_PTR, _ARRAY)
        if isinstance(e, c_ast.UnaryOp) and e.op == "&":
            return self._rooted_in_ram(e.expr)
        return False

    def _rooted_in_ram(self, e: c_ast.Node) -> bool:
        """An lvalue inside a RAM object: X, X.m, X[i], p->m, p[i] with p __data."""
        while isinstance(e, (c_ast.StructRef, c_ast.ArrayRef)):
            if isinstance(e, c_ast.StructRef) and e.type == "->" or isinstance(e, c_ast.ArrayRef) and \
                    isinstance(e.name, c_ast.ID) and self.kind(e.name.name) in (_DATA_PTR, _PTR):
                return isinstance(e.name, c_ast.ID) and self.kind(e.name.name) == _DATA_PTR
            e = e.name
        return isinstance(e, c_ast.ID) and self.kind(e.name) in (_ARRAY, _OBJECT, _DATA_PTR)


class _Walk(c_ast.NodeVisitor):
    """One pass over the unit with scopes: the verdict on every call of the
    candidate functions, and (``mark_locals``) the local pointers."""

    def __init__(self, candidates: dict[str, c_ast.FuncDef], marked: dict[str, set[str]], mark_locals: bool):
        self.scopes = _Scopes()
        self.candidates, self.marked, self.mark_locals = candidates, marked, mark_locals
        self.ok: dict[tuple[str, int], bool] = {}  # (function, parameter index) -> every call so far in RAM
        self.assigned: set[str] = set()
        self.locals: list[c_ast.Decl] = []

    def visit_FuncDef(self, node: c_ast.FuncDef) -> None:
        params = {}
        for p in (node.decl.type.args.params if node.decl.type.args else []):
            if isinstance(p, c_ast.Decl) and p.name:
                params[p.name] = _kind(p, p.name in self.marked.get(node.decl.name, set()))
        self.assigned = _assigned(node)
        self.scopes.push(params)
        self.visit(node.body)
        self.scopes.pop()

    def visit_Compound(self, node: c_ast.Compound) -> None:
        self.scopes.push()
        for item in node.block_items or []:
            self.visit(item)
        self.scopes.pop()

    def visit_Decl(self, node: c_ast.Decl) -> None:
        if node.init is not None:
            self.visit(node.init)
        if isinstance(node.type, c_ast.FuncDecl) or not node.name:
            return
        data = isinstance(node.type, c_ast.PtrDecl) and isinstance(node.type.type, c_ast.TypeDecl) and \
            node.init is not None and len(self.scopes.stack) > 1 and node.name not in self.assigned and \
            "static" not in (node.storage or []) and self.scopes.in_ram(node.init)
        if data and self.mark_locals:
            self.locals.append(node)
        self.scopes.declare(node.name, _kind(node, data))

    def visit_FuncCall(self, node: c_ast.FuncCall) -> None:
        name = node.name.name if isinstance(node.name, c_ast.ID) else None
        if name in self.candidates:
            args = node.args.exprs if node.args else []
            for k, p in enumerate(_params(self.candidates[name])):
                if _is_pointer(p):
                    here = k < len(args) and self.scopes.in_ram(args[k])
                    self.ok[name, k] = self.ok.get((name, k), True) and here
        self.generic_visit(node)


class _Named(c_ast.NodeVisitor):
    """Functions named other than by a call (their address is taken)."""

    def __init__(self):
        self.escaped: set[str] = set()
        self.called: set[str] = set()

    def visit_FuncCall(self, node: c_ast.FuncCall) -> None:
        if isinstance(node.name, c_ast.ID):
            self.called.add(node.name.name)
        else:
            self.visit(node.name)
        if node.args is not None:
            self.visit(node.args)

    def visit_ID(self, node: c_ast.ID) -> None:
        self.escaped.add(node.name)


def _params(fdef: c_ast.FuncDef) -> list[c_ast.Decl | None]:
    args = fdef.decl.type.args
    return [p if isinstance(p, c_ast.Decl) else None for p in (args.params if args else [])]


def _is_pointer(p: c_ast.Decl | None) -> bool:
    return p is not None and isinstance(p.type, c_ast.PtrDecl) and isinstance(p.type.type, c_ast.TypeDecl)


def _assigned(fdef: c_ast.FuncDef) -> set[str]:
    """Names a function's body assigns with `=` (a pointer given another
    one stays generic)."""
    class V(c_ast.NodeVisitor):
        names: set[str] = set()

        def visit_Assignment(self, node: c_ast.Assignment) -> None:
            if node.op == "=" and isinstance(node.lvalue, c_ast.ID):
                self.names.add(node.lvalue.name)
            self.generic_visit(node)
    v = V()
    v.names = set()
    v.visit(fdef.body)
    return v.names


def _add_data(decl_type: c_ast.PtrDecl) -> None:
    if DATA not in decl_type.type.quals:
        decl_type.type.quals = [*decl_type.type.quals, DATA]


def data_pointers(ast: c_ast.FileAST) -> list[str]:
    """Mark the unit's RAM-only pointer parameters and local pointers
    `__data`, in place; returns them ("function.parameter", or the local's
    name)."""
    named = _Named()
    named.visit(ast)
    candidates = {ext.decl.name: ext for ext in ast.ext if isinstance(ext, c_ast.FuncDef)
                  and "static" in (ext.decl.storage or []) and ext.decl.name not in named.escaped
                  and ext.decl.name in named.called}
    marked: dict[str, set[str]] = {name: set() for name in candidates}
    while True:  # a parameter passed on as an argument may become __data in turn
        walk = _Walk(candidates, marked, False)
        walk.visit(ast)
        grown = False
        for (name, k), ok in walk.ok.items():
            p = _params(candidates[name])[k]
            if ok and p.name not in marked[name] and p.name not in _assigned(candidates[name]):
                marked[name].add(p.name)
                grown = True
        if not grown:
            break
    prototypes: dict[str, list[c_ast.FuncDecl]] = {}
    for ext in ast.ext:
        if isinstance(ext, c_ast.Decl) and isinstance(ext.type, c_ast.FuncDecl):
            prototypes.setdefault(ext.name, []).append(ext.type)
    done = []
    for name, params in marked.items():
        positions = [k for k, p in enumerate(_params(candidates[name])) if p is not None and p.name in params]
        for fd in [candidates[name].decl.type, *prototypes.get(name, [])]:
            args = fd.args.params if fd.args else []
            for k in positions:
                if k < len(args) and _is_pointer(args[k]):
                    _add_data(args[k].type)
        done += [f"{name}.{p}" for p in sorted(params)]
    walk = _Walk(candidates, marked, True)
    walk.visit(ast)
    for decl in walk.locals:
        _add_data(decl.type)
        done.append(decl.name)
    return sorted(done)
