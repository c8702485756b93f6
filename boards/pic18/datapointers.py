"""Pointer parameters that only ever point into RAM, made sdcc `__data`
pointers.

A plain C pointer is a generic pointer for sdcc's pic16 port: three bytes,
the third telling RAM, program memory or EEPROM apart, and every access
through it a call of __gptrget/__gptrput. Generated code calls each
actor's step function (a static function) with pointers to its state and
to its tokens, all in RAM: declared `__data`, those pointers are two bytes
and accessed through FSR0 directly, several times faster. The rule, per
translation unit and for static functions whose address is never taken: a
pointer parameter is `__data` when every call passes the address of a
non-const object (or an element or member of one), an array of one, or a
parameter that is itself `__data`. Nothing else changes; a `__data` pointer
converts to a generic one wherever one is expected.
"""

from __future__ import annotations

from pycparser import c_ast

DATA = "__data"


class _Uses(c_ast.NodeVisitor):
    """Calls of each function, and functions whose address is taken."""

    def __init__(self):
        self.calls: dict[str, list[tuple[c_ast.FuncCall, str | None]]] = {}
        self.escaped: set[str] = set()
        self.current: str | None = None

    def visit_FuncDef(self, node: c_ast.FuncDef) -> None:
        self.current = node.decl.name
        self.visit(node.body)
        self.current = None

    def visit_FuncCall(self, node: c_ast.FuncCall) -> None:
        if isinstance(node.name, c_ast.ID):
            self.calls.setdefault(node.name.name, []).append((node, self.current))
        else:
            self.visit(node.name)
        if node.args is not None:
            self.visit(node.args)

    def visit_ID(self, node: c_ast.ID) -> None:
        self.escaped.add(node.name)  # a function named other than in a call


def _const_objects(ast: c_ast.FileAST) -> set[str]:
    """File-scope objects in program memory (const, not pointers to const)."""
    out = set()
    for ext in ast.ext:
        if isinstance(ext, c_ast.Decl) and not isinstance(ext.type, c_ast.FuncDecl):
            node = ext.type
            while isinstance(node, c_ast.ArrayDecl):
                node = node.type
            if "const" in (getattr(node, "quals", None) or []):
                out.add(ext.name)
    return out


def _params(fdef: c_ast.FuncDef) -> list[c_ast.Decl | None]:
    args = fdef.decl.type.args
    return [p if isinstance(p, c_ast.Decl) else None for p in (args.params if args else [])]


def _is_pointer(p: c_ast.Decl | None) -> bool:
    return p is not None and isinstance(p.type, c_ast.PtrDecl) and isinstance(p.type.type, c_ast.TypeDecl)


def _in_ram(e: c_ast.Node, rom: set[str], data_params: set[str], arrays: set[str]) -> bool:
    """Does this pointer-valued expression point into RAM for sure?"""
    if isinstance(e, c_ast.Cast):
        return _in_ram(e.expr, rom, data_params, arrays)
    if isinstance(e, c_ast.BinaryOp) and e.op in ("+", "-"):
        return _in_ram(e.left, rom, data_params, arrays)
    if isinstance(e, c_ast.ID):
        return e.name in data_params or (e.name in arrays and e.name not in rom)
    if isinstance(e, c_ast.UnaryOp) and e.op == "&":
        return _rooted_in_ram(e.expr, rom, data_params)
    return False


def _rooted_in_ram(e: c_ast.Node, rom: set[str], data_params: set[str]) -> bool:
    """An lvalue inside a RAM object: X, X.m, X[i], p->m, p[i] with p __data."""
    while isinstance(e, (c_ast.StructRef, c_ast.ArrayRef)):
        if isinstance(e, c_ast.StructRef) and e.type == "->":
            return isinstance(e.name, c_ast.ID) and e.name.name in data_params
        e = e.name
    if isinstance(e, c_ast.ID):
        return e.name not in rom or e.name in data_params
    return False


def _arrays(ast: c_ast.FileAST) -> set[str]:
    class V(c_ast.NodeVisitor):
        names: set[str] = set()

        def visit_Decl(self, node: c_ast.Decl) -> None:
            if isinstance(node.type, c_ast.ArrayDecl) and node.name:
                self.names.add(node.name)
            self.generic_visit(node)
    v = V()
    v.names = set()
    v.visit(ast)
    return v.names


def _assigned(fdef: c_ast.FuncDef) -> set[str]:
    """Names a function's body assigns with `=` (a parameter given another
    pointer stays generic)."""
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


class _Locals(c_ast.NodeVisitor):
    """Local pointers initialised with a RAM address and never given
    another (inline.py's parameters, for one)."""

    def __init__(self, rom: set[str], arrays: set[str], data: set[str]):
        self.rom, self.arrays, self.data = rom, arrays, data
        self.found: list[c_ast.Decl] = []
        self.assigned: set[str] = set()

    def visit_FuncDef(self, node: c_ast.FuncDef) -> None:
        self.assigned = _assigned(node)
        self.visit(node.body)

    def visit_Decl(self, node: c_ast.Decl) -> None:
        if _is_pointer(node) and node.init is not None and node.name not in self.assigned \
                and "static" not in (node.storage or []) \
                and _in_ram(node.init, self.rom, self.data, self.arrays):
            self.data.add(node.name)
            self.found.append(node)
        self.generic_visit(node)


def data_pointers(ast: c_ast.FileAST) -> list[str]:
    """Mark the RAM-only pointer parameters of the unit's static functions
    and its RAM-only local pointers `__data`, in place; returns them as
    "function.name" (or the local's name)."""
    uses = _Uses()
    uses.visit(ast)
    rom, arrays = _const_objects(ast), _arrays(ast)
    funcs = {ext.decl.name: ext for ext in ast.ext if isinstance(ext, c_ast.FuncDef)
             and "static" in (ext.decl.storage or []) and ext.decl.name not in uses.escaped}
    marked: dict[str, set[str]] = {name: set() for name in funcs}
    changed = True
    while changed:  # a parameter passed on as an argument may become __data in turn
        changed = False
        for name, fdef in funcs.items():
            calls = uses.calls.get(name, [])
            if not calls:
                continue
            assigned = _assigned(fdef)
            for k, p in enumerate(_params(fdef)):
                if not _is_pointer(p) or p.name in marked[name] or p.name in assigned:
                    continue
                if all(call.args is not None and k < len(call.args.exprs)
                       and _in_ram(call.args.exprs[k], rom, marked.get(caller, set()) if caller else set(), arrays)
                       for call, caller in calls):
                    marked[name].add(p.name)
                    changed = True
    prototypes: dict[str, list[c_ast.FuncDecl]] = {}
    for ext in ast.ext:
        if isinstance(ext, c_ast.Decl) and isinstance(ext.type, c_ast.FuncDecl):
            prototypes.setdefault(ext.name, []).append(ext.type)
    done = []
    for name, params in marked.items():
        positions = [k for k, p in enumerate(_params(funcs[name])) if p is not None and p.name in params]
        for fd in [funcs[name].decl.type, *prototypes.get(name, [])]:
            args = fd.args.params if fd.args else []
            for k in positions:
                if k < len(args) and _is_pointer(args[k]) and DATA not in args[k].type.type.quals:
                    args[k].type.type.quals = [*args[k].type.type.quals, DATA]
        done += [f"{name}.{p}" for p in sorted(params)]
    locals_ = _Locals(rom, arrays, {p for params in marked.values() for p in params})
    locals_.visit(ast)
    for decl in locals_.found:
        if DATA not in decl.type.type.quals:
            decl.type.type.quals = [*decl.type.type.quals, DATA]
        done.append(decl.name)
    return sorted(done)
